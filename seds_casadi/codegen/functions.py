"""CasADi Functions compiled to C, and a low-overhead numeric evaluator.

:func:`compile_functions` writes CasADi's own C for a list of Functions into one shared library
(through the cache of :mod:`seds_casadi.codegen.cache`) and loads them back with
``casadi.external``; with no compiler, or if the build fails, the functions are returned unchanged
and CasADi's virtual machine evaluates them (same results, about 10x slower).
:class:`FastEvaluator` calls a Function through fixed numpy buffers (about 0.2 us of overhead
instead of 10-30 us for ``f(x)`` from Python).
"""

from __future__ import annotations

import logging
import os
import shutil
import tempfile
import threading

import casadi as ca
import numpy as np

from .cache import CompileError, compiler_available, shared_library

_LOG = logging.getLogger(__name__)
_LOCK = threading.Lock()
_LOADED: dict[str, tuple[ca.Function, ...]] = {}


def _casadi_source(funcs: list[ca.Function]) -> bytes:
    gen = ca.CodeGenerator("seds_kernels.c", {"with_header": False})
    for f in funcs:
        gen.add(f)
    tmpdir = tempfile.mkdtemp(prefix="seds_cg_")
    try:
        gen.generate(tmpdir + os.sep)
        with open(os.path.join(tmpdir, "seds_kernels.c"), "rb") as fh:
            return fh.read()
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)


def compile_functions(funcs: list[ca.Function], flags: tuple[str, ...] = ("-O1",)
                      ) -> list[ca.Function]:
    """Compile CasADi Functions to C (one shared library, cached by source hash) and load them.

    Parameters
    ----------
    funcs : list of casadi.Function
    flags : tuple of str
        Optimisation flags for the compiler (``-O1``: ``-O2`` measured no faster for the SEDS
        kernels).

    Returns
    -------
    list of casadi.Function
        The compiled functions, or ``funcs`` unchanged when no compiler is available or the
        build fails (a warning is logged).
    """
    if compiler_available() is None:
        return list(funcs)
    src = _casadi_source(funcs)
    names = ",".join(f.name() for f in funcs)
    try:
        lib = shared_library(src, "seds_kernels", tuple(flags))
    except CompileError as exc:
        _LOG.warning("compiling %s failed (%s); using CasADi's virtual machine", names, exc)
        return list(funcs)
    with _LOCK:
        if lib not in _LOADED:
            _LOADED[lib] = tuple(ca.external(f.name(), lib) for f in funcs)
        return list(_LOADED[lib])


class FastEvaluator:
    """Low-overhead calls of a CasADi Function through fixed numpy buffers (``Function.buffer``).

    Not thread-safe: use one evaluator per thread.

    Parameters
    ----------
    f : casadi.Function
        Dense inputs and outputs.
    """

    def __init__(self, f: ca.Function) -> None:
        self.function = f
        self._in = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        self._out = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        self._buf, self._eval = f.buffer()
        for i, a in enumerate(self._in):
            self._buf.set_arg(i, memoryview(a))
        for i, a in enumerate(self._out):
            self._buf.set_res(i, memoryview(a))

    def __call__(self, *args) -> np.ndarray:
        """Evaluate; returns a copy of the first output as a flat array."""
        if len(args) != len(self._in):
            raise TypeError(f"{self.function.name()} takes {len(self._in)} arguments, "
                            f"got {len(args)}")
        for a, v in zip(self._in, args):
            a[...] = v
        self._eval()
        return self._out[0].copy()

    def outputs(self) -> list[np.ndarray]:
        """Copies of every output of the last call, as flat arrays."""
        return [o.copy() for o in self._out]


def batch_evaluate(f: ca.Function, *columns: np.ndarray) -> list[np.ndarray]:
    """Evaluate a point-wise Function over many points at once.

    Parameters
    ----------
    f : casadi.Function
        Inputs of shape (n_i, 1) (or scalars), outputs of shape (m_j, 1).
    *columns : arrays, shape (n_i, n_points) or scalars
        One array per input; scalars are broadcast to every point.

    Returns
    -------
    list of array, shape (n_points, m_j)
        Each output, one row per point.

    Notes
    -----
    CasADi evaluates a Function called with ``n`` times as many columns as it declares as a map
    over the columns, in compiled or virtual-machine code: the expression is the one defined in
    CasADi, evaluated without a Python loop.
    """
    try:
        out = f.call([ca.DM(c) if np.ndim(c) else float(c) for c in columns])
        return [np.asarray(o).T.reshape(-1, f.size1_out(j)) for j, o in enumerate(out)]
    except Exception as exc:  # noqa: BLE001 - only an interrupt's consequence is replaced
        # a signal's KeyboardInterrupt raised while CasADi's SWIG code converts a DM (its
        # __array__) comes out as "SystemError: ... returned a result with an exception set":
        # the interrupt is raised as itself
        interrupt = interrupt_within(exc)
        if interrupt is None:
            raise
        raise interrupt from None


def interrupt_within(exc: BaseException) -> KeyboardInterrupt | None:
    """The ``KeyboardInterrupt`` that caused ``exc`` (its ``__cause__`` or ``__context__``
    chain), if any: C code of CasADi (SWIG) reports an interrupt raised inside it as a
    ``SystemError``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


class CachedFunctionMixin:
    """For model classes with a ``to_casadi()``: builds that Function once, on first use.

    ``self._function()`` returns the cached Function; pickling drops it (it is rebuilt after
    unpickling), so models still travel to worker processes.
    """

    def _function(self) -> ca.Function:
        f = self.__dict__.get("_f")
        if f is None:
            f = self.__dict__["_f"] = self.to_casadi()
        return f

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_f", None)
        state.pop("_compiled", None)   # a compiled form of it (HittingMotion.compiled)
        return state
