"""nonholo.codegen: code generation, from the mechanisms' and the integrator's Python to the
modules numba compiles and the C extension modules built from them.

One configuration per backend:

- :mod:`~nonholo.codegen.python_config`: :class:`PythonConfig` (``PYTHON``), modules in the
  subset numba compiles, in ``nonholo/generated``;
- :mod:`~nonholo.codegen.c_config`: :class:`CConfig` (``C``), CPython extension modules,
  their C in ``nonholo/generated/native``, the compiler's flags.

The modules by job:

- :mod:`~nonholo.codegen.emit`: the generated files — ``mechanism_files``,
  ``python_kernels`` (Python), ``kernel_source``, ``native_files`` (C);
- :mod:`~nonholo.codegen.inline`: functions with calls expanded in place
  (``inlined_module``, ``expand``);
- :mod:`~nonholo.codegen.c_subset`, :mod:`~nonholo.codegen.c_translation`,
  :mod:`~nonholo.codegen.c_extension`: Python to C — the translated subset (``Function``,
  ``TranslationError``), ``translate``, ``extension_source``;
- :mod:`~nonholo.codegen.build`: the compiler and the native modules (``load``,
  ``native_kernels``, ``enabled``, ``compiler``);
- :mod:`~nonholo.codegen.cache`: the disk caches, verified by hash (``read_entry``,
  ``write_entry``, ``import_verified``, ``cached_source``, ``cache_dir``, ``digest``);
- :mod:`~nonholo.codegen.mechanism_modules`: the generated modules of mechanisms defined in
  a process (``symbolic_module``, ``equations_module``, ``load_source``).

Code generation imports nothing of the package above ``nonholo.generated``: what the
integrator contributes (its source, the functions translated with its kernels) it passes
in (:mod:`nonholo.integrate.compiled`).
"""

__all__ = ["build", "c_config", "c_extension", "c_subset", "c_translation", "cache", "emit", "inline",
           "mechanism_modules", "python_config"]
