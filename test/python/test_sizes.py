"""Issue 31, 8: rooms of one concept (test/check_sizes.py): no source file over 600 lines and
no procedure over 100 lines, unless the file's header says why in a sentence starting with
`Size:`; an oversized file or procedure fails the check, named with its length."""
from __future__ import annotations

import subprocess
import sys

from simulator import ROOT

CHECKER = ROOT / "test" / "check_sizes.py"
sys.path.insert(0, str(CHECKER.parent))
import check_sizes  # noqa: E402


def _check(root) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECKER), str(root)], capture_output=True,
                          text=True, timeout=60)


def _fortran(name: str, body_lines: int, header: str = "") -> str:
    """A module with one subroutine of body_lines lines between its first and last line."""
    body = "".join(f"        x = x + {i}\n" for i in range(body_lines - 2))
    return (f"{header}module {name}\n    implicit none\ncontains\n"
            f"    pure subroutine grow(x)\n{body}    end subroutine grow\nend module {name}\n")


def test_the_tree_keeps_its_rooms():
    result = _check(ROOT)
    assert result.returncode == 0, result.stderr


def test_an_oversized_file_and_procedure_fail(tmp_path):
    (tmp_path / "src" / "base").mkdir(parents=True)
    (tmp_path / "src" / "base" / "chain_big.f90").write_text(
        _fortran("chain_big", 101) + "! filler\n" * 600)
    (tmp_path / "src" / "base" / "chain_fits.f90").write_text(_fortran("chain_fits", 100))
    package = tmp_path / "python" / "impactchain"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text('"""The package."""\n')
    (package / "long.py").write_text(
        "def long():\n" + "    x = 1\n" * 100 + "\n\ndef short():\n    return 1\n")
    # an installed or built copy of the package is not its source
    copy = tmp_path / "build" / "impactchain"
    copy.mkdir(parents=True)
    (copy / "__init__.py").write_text((package / "long.py").read_text())
    result = _check(tmp_path)
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        "check_sizes: src/base/chain_big.f90: 705 lines (at most 600)",
        "check_sizes: src/base/chain_big.f90:4: procedure grow has 101 lines (at most 100)",
        "check_sizes: python/impactchain/long.py:1: procedure long has 101 lines (at most 100)",
    ], result.stderr


def test_a_header_sentence_excuses_a_file(tmp_path):
    (tmp_path / "src").mkdir()
    why = "!> A module.\n!> Size: the loop stays whole so that the compiler\n!> inlines it.\n"
    (tmp_path / "src" / "chain_why.f90").write_text(_fortran("chain_why", 120, why))
    # the marker alone, or with a word or two, is no reason
    (tmp_path / "src" / "chain_bare.f90").write_text(_fortran("chain_bare", 120, "!> Size:\n"))
    (tmp_path / "src" / "chain_short.f90").write_text(
        _fortran("chain_short", 120, "!> Size: it is too big.\n"))
    result = _check(tmp_path)
    assert result.returncode == 1
    assert [line.split(":")[1].strip() for line in result.stderr.splitlines()] == [
        "src/chain_bare.f90", "src/chain_short.f90"], result.stderr
    assert result.stdout.splitlines() == [
        "check_sizes: src/chain_why.f90: 127 lines, excused: the loop stays whole so that "
        "the compiler inlines it."], result.stdout


def test_contained_procedures_count_on_their_own():
    text = """module m
contains
    subroutine host()
        integer :: a
        call inner()
    contains
        subroutine inner()
            a = 1; a = 2
            if (a > 1) then
                a = &
                    3
            end if
        end subroutine inner
        pure integer function twice(k) result(j)
            integer, intent(in) :: k
            j = 2*k
        end function
    end subroutine host
    module procedure separate
    end procedure separate
end module m
"""
    assert check_sizes.fortran_procedures(text) == [
        ("inner", 7, 7), ("twice", 14, 4), ("host", 3, 5), ("separate", 19, 2)]


def test_interface_blocks_declare_no_procedure():
    text = """module m
    abstract interface
        subroutine callback_i(x)
            real, intent(in) :: x
        end subroutine callback_i
    end interface
    interface
        module function separate(x) result(y)
            real, intent(in) :: x
            real :: y
        end function
    end interface
contains
    real(kind=8) function f(x)
        real(8), intent(in) :: x
        f = x
    end function f
end module m
"""
    assert check_sizes.fortran_procedures(text) == [("f", 14, 4)]


def test_python_defs_count_without_their_nested_defs():
    text = '''"""Module."""


class Box:
    def method(self):
        def helper():
            return 1
        return helper()


async def run():
    return 2
'''
    assert check_sizes.python_procedures(text) == [
        ("Box.method.helper", 6, 2), ("Box.method", 5, 2), ("run", 11, 2)]
