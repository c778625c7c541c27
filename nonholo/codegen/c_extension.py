"""The CPython extension module of translated functions: argument conversion, the GIL
released while a function runs, the module's ``SOURCE_DIGEST``.
"""
from __future__ import annotations

from pathlib import Path

from . import c_subset, c_translation
from .c_subset import KINDS, Function, parameters
from .c_translation import translate


_PRELUDE = r"""#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <alloca.h>

/* An argument of a wrapper: a C-contiguous array of the given type and dimensions. An
   argument only read is converted (a new reference in *hold, released by the caller); an
   argument written must already be such an array (a copy would lose the writes). */
static int nh_array(PyObject *o, int type, int nd, int written, const char *fname, const char *arg,
                    PyObject **hold, void **data, int64_t *shape)
{
    PyArrayObject *a = (PyArrayObject *)o;
    *hold = NULL;
    if (!(PyArray_Check(o) && PyArray_TYPE(a) == type && PyArray_NDIM(a) == nd && PyArray_IS_C_CONTIGUOUS(a))) {
        if (written || !(PyArray_Check(o) || PySequence_Check(o))) {
            PyErr_Format(PyExc_TypeError, "%s: argument '%s' must be a C-contiguous %d-d%s array of %s",
                         fname, arg, nd, written ? " writable" : "", type == NPY_FLOAT64 ? "float64" : "int64");
            return 0;
        }
        *hold = PyArray_FROMANY(o, type, nd, nd, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
        if (*hold == NULL) return 0;
        a = (PyArrayObject *)*hold;
    } else if (written && !PyArray_ISWRITEABLE(a)) {
        PyErr_Format(PyExc_ValueError, "%s: argument '%s' is read-only", fname, arg);
        return 0;
    }
    *data = PyArray_DATA(a);
    for (int i = 0; i < nd; i++) shape[i] = (int64_t)PyArray_DIM(a, i);
    return 1;
}
"""


def _wrapper(fn: Function) -> str:
    """A METH_FASTCALL wrapper of ``fn`` (arguments checked, the GIL released while it runs)."""
    params = parameters(fn.func)
    arrays = [p for p in params if KINDS[fn.kinds[p]][1]]
    lines = [f"static PyObject *py_{fn.cname}(PyObject *self, PyObject *const *args, Py_ssize_t nargs)", "{"]
    lines.append(f"    if (nargs != {len(params)}) {{ PyErr_Format(PyExc_TypeError, \"{fn.cname} takes {len(params)} arguments (%zd given)\", nargs); return NULL; }}")
    if arrays:
        lines.append(f"    PyObject *hold[{len(arrays)}] = {{NULL}};")
        lines.append("    PyObject *result = NULL;")
    release = f"for (int _h = 0; _h < {len(arrays)}; _h++) Py_XDECREF(hold[_h]);" if arrays else ""
    fail = "goto done;" if arrays else "return NULL;"
    call = []
    decl = []
    for i, p in enumerate(params):
        ctype, nd = KINDS[fn.kinds[p]]
        if nd:
            npy = "NPY_FLOAT64" if ctype == "double" else "NPY_INT64"
            h = arrays.index(p)
            decl.append(f"    void *{p}_d = NULL; int64_t {p}_sh[{nd}] = {{0}};")
            lines.append(f"    if (!nh_array(args[{i}], {npy}, {nd}, {int(p in fn.written)}, \"{fn.cname}\", \"{p}\", "
                         f"&hold[{h}], &{p}_d, {p}_sh)) {fail}")
            call.append(f"({ctype} *){p}_d")
            call.extend(f"{p}_sh[{j}]" for j in range(nd))
        elif ctype == "double":
            decl.append(f"    double {p} = 0;")
            lines.append(f"    {p} = PyFloat_AsDouble(args[{i}]);")
            lines.append(f"    if ({p} == -1.0 && PyErr_Occurred()) {fail}")
            call.append(p)
        elif ctype == "int64_t":
            decl.append(f"    int64_t {p} = 0;")
            lines.append(f"    {p} = (int64_t)PyLong_AsLongLong(args[{i}]);")
            lines.append(f"    if ({p} == -1 && PyErr_Occurred()) {fail}")
            call.append(p)
        else:
            decl.append(f"    int {p} = 0;")
            lines.append(f"    {p} = PyObject_IsTrue(args[{i}]);")
            lines.append(f"    if ({p} < 0) {fail}")
            call.append(p)
    rets = fn.returns
    box = {"double": "PyFloat_FromDouble", "int64_t": "PyLong_FromLongLong", "int": "PyBool_FromLong"}
    for i, t in enumerate(rets):
        decl.append(f"    {t} r{i} = 0;")
    if len(rets) > 1:
        call.extend(f"&r{i}" for i in range(len(rets)))
    lines.append("    Py_BEGIN_ALLOW_THREADS")
    lines.append(f"    {'r0 = ' if len(rets) == 1 else ''}{fn.cname}({', '.join(call)});")
    lines.append("    Py_END_ALLOW_THREADS")
    if len(rets) > 1:
        value = f"nh_tuple({len(rets)}, " + ", ".join(f"{box[t]}(r{i})" for i, t in enumerate(rets)) + ")"
    elif rets:
        value = f"{box[rets[0]]}(r0)"
    else:
        value = "Py_NewRef(Py_None)"
    if arrays:
        lines.append(f"    result = {value};")
        lines.append("done:")
        lines.append(f"    {release}")
        lines.append("    return result;")
    else:
        lines.append(f"    return {value};")
    lines.append("}")
    return "\n".join(lines[:2] + decl + lines[2:]) + "\n"


_TUPLE = r"""
/* A tuple of new references (stolen). */
static PyObject *nh_tuple(Py_ssize_t n, ...)
{
    va_list ap;
    PyObject *t = PyTuple_New(n);
    va_start(ap, n);
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *o = va_arg(ap, PyObject *);
        if (t == NULL || o == NULL) { Py_XDECREF(o); continue; }
        PyTuple_SET_ITEM(t, i, o);
    }
    va_end(ap);
    if (t != NULL) for (Py_ssize_t i = 0; i < n; i++) if (PyTuple_GET_ITEM(t, i) == NULL) { Py_DECREF(t); return NULL; }
    return t;
}
"""


def extension_source(module_name: str, header: str, functions: list[Function], digest: str) -> str:
    """The C source of a CPython extension module exposing translated functions.

    Parameters
    ----------
    module_name : str
        The module's full name (its last dotted part is the init name).
    header : str
        The comment at the top of the source.
    functions : list of Function
        The functions, translated in order; the exported ones are exposed under their C
        names.
    digest : str
        The module's attribute ``SOURCE_DIGEST`` (of what it was translated from).

    Returns
    -------
    str
        The C source.

    Raises
    ------
    TranslationError
        For a construct outside the translated subset.
    """
    body, _ = translate(functions)
    short = module_name.rsplit(".", 1)[-1]
    exported = [f for f in functions if f.exported]
    wrappers = "\n".join(_wrapper(f) for f in exported)
    table = "\n".join(f'    {{"{f.cname}", (PyCFunction)(void (*)(void))py_{f.cname}, METH_FASTCALL, NULL}},' for f in exported)
    return f"""/* {header} */
{_PRELUDE}#include <stdarg.h>
{_TUPLE}
{body}
{wrappers}
static PyMethodDef methods[] = {{
{table}
    {{NULL, NULL, 0, NULL}}
}};

static struct PyModuleDef moduledef = {{PyModuleDef_HEAD_INIT, "{module_name}", NULL, -1, methods}};

PyMODINIT_FUNC PyInit_{short}(void)
{{
    import_array();
    PyObject *m = PyModule_Create(&moduledef);
    if (m == NULL) return NULL;
    if (PyModule_AddStringConstant(m, "SOURCE_DIGEST", "{digest}") < 0) {{ Py_DECREF(m); return NULL; }}
    return m;
}}
"""


def translator_sources() -> list[str]:
    """The sources of the translation (the subset, the translator, this module): a native
    module's digest covers them, so that a change in the translation rebuilds it.

    Returns
    -------
    list of str
        The modules' sources.
    """
    return [Path(m.__file__).read_text() for m in (c_subset, c_translation)] + [Path(__file__).read_text()]
