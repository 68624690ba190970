"""Entry point of ``python -m post``."""

from post.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
