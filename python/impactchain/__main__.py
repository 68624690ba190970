"""Entry point of ``python -m impactchain``."""

from impactchain.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
