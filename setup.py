"""Build of the native kernels: the C that `nonholo derive` writes to nonholo/generated/native/.

Every ``nonholo/generated/native/<name>.c`` becomes the extension module
``nonholo.generated.native.<name>``, compiled with the system's C compiler. Each is optional:
where no compiler is found or a build fails, the install goes on and the kernels are
compiled at run time (by the compiler, or by numba; see ``nonholo/codegen/build.py``).
The rest of the configuration is in ``pyproject.toml``.
"""
from pathlib import Path

import numpy
from setuptools import Extension, setup

HERE = Path(__file__).parent
# the flags of nonholo.codegen.c_config.CFLAGS (no contraction into fused multiply-adds)
FLAGS = ["-O2", "-fno-math-errno", "-ffp-contract=off", "-std=gnu99",
         "-Wno-unused-variable", "-Wno-unused-but-set-variable", "-Wno-unused-function"]

extensions = [
    Extension(f"nonholo.generated.native.{c.stem}", [str(c.relative_to(HERE))],
              include_dirs=[numpy.get_include()], extra_compile_args=FLAGS, optional=True)
    for c in sorted((HERE / "nonholo" / "generated" / "native").glob("*.c"))
]

setup(ext_modules=extensions)
