"""House rules the linters do not check: no function over 60 lines outside the compiled kernels (the
orchestrators are split along their own steps)."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "wrp_eval"
MAX_LINES = 60


def test_no_function_over_sixty_lines_outside_the_kernels():
    long = []
    for file in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(file.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            compiled = any(ast.unparse(d) == "kernel" for d in node.decorator_list)
            lines = node.end_lineno - node.lineno + 1
            if lines > MAX_LINES and not compiled:
                long.append(f"{file.relative_to(PACKAGE)}:{node.lineno} {node.name} ({lines} lines)")
    assert not long, "functions over 60 lines: " + ", ".join(long)
