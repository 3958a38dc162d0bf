"""The kernels' numba cache follows an edit of any kernel module, not only the kernel's own.

numba stamps a cached function with its own file: a kernel that inlines a helper or reads a
constant from another module would keep stale machine code after an edit there.
vibroimpact._kernel_cache stamps every kernel of a package with all of its kernel modules;
this checks it on a two-module package compiled in a subprocess, with numba's cache on disk.
"""
import os
from pathlib import Path
import subprocess
import sys

SRC = Path(__file__).resolve().parents[1] / "src"

JIT = '''from numba import njit
from vibroimpact._kernel_cache import kernel_decorator
kernel = kernel_decorator(njit, __file__, ("constants.py", "outer.py"), error_model="numpy")
'''
OUTER = '''from toy._jit import kernel
from toy.constants import SCALE
@kernel
def outer(x):
    return SCALE * x
'''


def _run(root, env):
    code = "from toy.outer import outer; print(outer(2.0))"
    out = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True,
                         text=True, check=True, timeout=300)
    return float(out.stdout.split()[-1])


def test_an_edit_of_another_kernel_module_recompiles(tmp_path):
    pkg = tmp_path / "toy"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "_jit.py").write_text(JIT)
    (pkg / "outer.py").write_text(OUTER)
    (pkg / "constants.py").write_text("SCALE = 3.0\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(SRC)]),
               NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    assert _run(tmp_path, env) == 6.0
    assert _run(tmp_path, env) == 6.0                      # from the cache
    assert any((tmp_path / "cache").rglob("*.nbi"))
    (pkg / "constants.py").write_text("SCALE = 5.0\n")    # outer.py untouched
    assert _run(tmp_path, env) == 10.0
