"""Code lines of the ftcal package, per subpackage: lines that hold code, not blank, comment or docstring lines.

A line counts when a token of code (not a comment) lies on it and it is not part of a module's, class' or
function's docstring; a string spanning lines in code counts each of its lines. Prints each subpackage, the
total, the total without the command line (``cli``) and the command line's share.

Run: ``python benchmarks/code_lines.py`` (or give the package folder: ``python benchmarks/code_lines.py ftcal``).
"""

from __future__ import annotations

import ast
import io
import sys
import tokenize
from collections import Counter
from pathlib import Path

_NOT_CODE = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}


def code_line_numbers(source: str) -> set[int]:
    """The numbers of the lines of ``source`` that hold code (a token that is not a comment, outside docstrings)."""
    docstrings = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and \
                    isinstance(first.value.value, str):
                docstrings.update(range(first.lineno, first.end_lineno + 1))
    lines = set()
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type not in _NOT_CODE:
            lines.update(n for n in range(token.start[0], token.end[0] + 1) if n not in docstrings)
    return lines


def code_lines(path: Path) -> int:
    """The number of code lines of the Python file at ``path``."""
    return len(code_line_numbers(path.read_text()))


def main(root: Path) -> None:
    per_package: Counter[str] = Counter()
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root).parts
        per_package[parts[0] if len(parts) > 1 else "(top level)"] += code_lines(path)
    total = sum(per_package.values())
    for name, count in per_package.most_common():
        print(f"{name:18s} {count:6d}")
    print(f"{'total':18s} {total:6d}")
    print(f"{'without cli':18s} {total - per_package['cli']:6d}   (cli: {per_package['cli'] / total:.1%} of the code)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "ftcal")
