"""$(eval) refuses a value too large before it is built (launch/eval_expr.py): each operation's
result size is computed from its operands, nested repetition included, so the refusal comes at
once and with little memory. The expressions are loaded from launch files inside a guard
process (RLIMIT_AS 1 GB, 20 CPU seconds): code that builds the value first fails the test there,
not by exhausting the test machine.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import textwrap

import pytest

from twil_control.launch.eval_expr import MAX_SIZE, EvalError, evaluate

TOO_LARGE = {
    "[[1]*99999]*99999": "39,999,799,998",  # 800 kB of list, 40 GB once printed
    "str(['a'*99999]*99999)": "10,000,399,995",
    "[[[0]*1000]*1000]*1000": "4,006,000",
}

GUARD = """
    import json, sys
    from pathlib import Path
    from twil_control.launch.loader import load_launch
    out = {}
    for path in sys.argv[1:]:
        try:
            load_launch(Path(path), {})
            out[path] = "loaded"
        except MemoryError:
            out[path] = "MemoryError"
        except Exception as error:
            out[path] = str(error)
    print(json.dumps(out))
"""


def test_values_too_large_are_refused_before_they_are_built(tmp_path):
    paths = []
    for i, expression in enumerate(TOO_LARGE):
        launch = tmp_path / f"eval{i}.launch"
        launch.write_text(
            f'<launch>\n  <arg name="x" value="$(eval {expression})"/>\n'
            '  <param name="p" value="$(arg x)"/>\n</launch>\n'
        )
        paths.append(str(launch))

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        resource.setrlimit(resource.RLIMIT_CPU, (20, 21))

    proc = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(GUARD), *paths],
        capture_output=True,
        text=True,
        preexec_fn=limit,
        timeout=120,
    )
    lines = proc.stdout.strip().splitlines()
    assert proc.returncode == 0 and lines, (
        f"the guard process died ({proc.returncode}): {proc.stderr[-1500:]}"
    )
    got = json.loads(lines[-1])
    for path, (expression, size) in zip(paths, TOO_LARGE.items()):
        assert f"$(eval {expression}): the result would be about {size} characters long" in got[path], got


def test_values_within_the_bound_still_evaluate():
    names = {"n": 3}.__getitem__
    assert evaluate("str([[0]*3]*2)", names, {}) == "[[0, 0, 0], [0, 0, 0]]"
    assert evaluate("'ab' * n + 'c'", names, {}) == "abababc"
    assert len(evaluate("'x' * 99999", names, {})) == 99999
    with pytest.raises(EvalError, match=f"more than the {MAX_SIZE:,} allowed"):
        evaluate("[['y' * 9999] * 99] * 99", names, {})
