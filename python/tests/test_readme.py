"""The README's Python snippet runs as written (with matplotlib's non-interactive backend, so
that `plt.show()` returns at once)."""

import os
import pathlib
import re
import subprocess
import sys

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def test_the_readme_python_snippet_runs_as_written():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README.md has no python block"
    env = dict(os.environ, MPLBACKEND="Agg")
    for code in blocks:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
        assert out.returncode == 0, out.stderr
        # The snippet prints the tip (numpy, m) and the iteration count.
        assert "[" in out.stdout, out.stdout
