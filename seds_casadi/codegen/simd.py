"""A CasADi SX step function compiled as a loop over many states, written for the C compiler's
vectoriser.

CasADi's own code generation evaluates a mapped function one state at a time, with a call per
state. For a ball model, where the same few hundred operations are applied to thousands of
shots, this module emits C that applies each step to a block of states in an ``omp simd`` loop,
repeats it for many steps with the block held in L1 cache, and stops a block early once every
state in it is finished (2.3-3.4x CasADi's kernel on the ball model). GCC 12 does not vectorise
the ball step's loop (``-fopt-info-vec``: ``fmax`` with its NaN rule, comparisons chained
through doubles, and ``exp`` in the hills field's step), so it runs one shot per instruction;
only the block's "all done" test is vectorised. The C is generated from the SX
function's instruction list, so it computes exactly the same expression as the CasADi kernel
(up to the compiler's floating-point contractions and the vector math library's exp/log, which
are within a few ulp).

The translator of an SX Function's instructions into C statements (:func:`instruction_lines`)
is shared with :mod:`seds_casadi.codegen.column_sum`.

Used by :class:`seds_casadi.minigolf.ball_kernel.BallKernel`; falls back to CasADi's kernel when
there is no C compiler, the step uses an operation not translated here (e.g. an interpolant
call), or the compiler fails.
"""

from __future__ import annotations

import ctypes
import hashlib
import threading
from concurrent.futures import ThreadPoolExecutor

import casadi as ca
import numpy as np

from .cache import CompileError, shared_library

__all__ = ["simd_source", "SimdLoop", "UnsupportedOperation", "instruction_lines", "VECTOR_MATH",
           "cpu_key", "load_library"]

_LOCK = threading.Lock()
_LOADED: dict[str, ctypes.CDLL] = {}

_BINARY = {ca.OP_ADD: "{0} + {1}", ca.OP_SUB: "{0} - {1}", ca.OP_MUL: "{0} * {1}",
           ca.OP_DIV: "{0} / {1}", ca.OP_FMIN: "fmin({0}, {1})", ca.OP_FMAX: "fmax({0}, {1})",
           ca.OP_LT: "({0} < {1} ? 1.0 : 0.0)", ca.OP_LE: "({0} <= {1} ? 1.0 : 0.0)",
           ca.OP_EQ: "({0} == {1} ? 1.0 : 0.0)", ca.OP_NE: "({0} != {1} ? 1.0 : 0.0)",
           ca.OP_AND: "({0} != 0.0 && {1} != 0.0 ? 1.0 : 0.0)",
           ca.OP_OR: "({0} != 0.0 || {1} != 0.0 ? 1.0 : 0.0)",
           ca.OP_IF_ELSE_ZERO: "({0} != 0.0 ? {1} : 0.0)", ca.OP_POW: "pow({0}, {1})",
           ca.OP_CONSTPOW: "pow({0}, {1})", ca.OP_ATAN2: "atan2({0}, {1})",
           ca.OP_COPYSIGN: "copysign({0}, {1})"}
_UNARY = {ca.OP_NEG: "-{0}", ca.OP_SQ: "{0} * {0}", ca.OP_TWICE: "2.0 * {0}",
          ca.OP_SQRT: "sqrt({0})", ca.OP_FABS: "fabs({0})", ca.OP_EXP: "exp({0})",
          ca.OP_LOG: "log({0})", ca.OP_SIN: "sin({0})", ca.OP_COS: "cos({0})",
          ca.OP_TAN: "tan({0})", ca.OP_ATAN: "atan({0})", ca.OP_TANH: "tanh({0})",
          ca.OP_NOT: "({0} == 0.0 ? 1.0 : 0.0)", ca.OP_INV: "1.0 / {0}",
          ca.OP_FLOOR: "floor({0})", ca.OP_ASSIGN: "{0}"}
# math functions glibc's libmvec has AVX2 versions of (declared below so GCC may call them)
VECTOR_MATH = ("exp", "log", "sin", "cos", "tan", "atan", "tanh", "pow", "atan2")


class UnsupportedOperation(ValueError):
    """The step function uses an operation this translator does not emit (e.g. a call)."""


def simd_source(step: ca.Function, name: str, done_index: int | None = None,
                block: int = 64, lookup: dict | None = None) -> str:
    """C source of ``void name(int n, int stride, int steps, double *S, const double *T)``.

    ``S`` holds ``n`` states column-wise (state component j of state i at ``S[j*stride + i]``);
    each is advanced ``steps`` times by ``step`` (an SX Function with one dense input and one
    dense output of the same size), in blocks of ``block`` states. With ``done_index``, a block
    stops once that component is non-zero for all its states (the step must then leave such a
    state unchanged, as the ball model does).

    With ``lookup``, the step has a second input, ``aux`` (``channels`` values), read by linear
    interpolation from the table ``T`` (a regular grid over two state components, the same
    layout and extrapolation as CasADi's "linear" interpolant: channel fastest, then x, then
    y): ``lookup = dict(ix=, iy=, x0=, dx=, nx=, y0=, dy=, ny=, channels=)``.

    Raises
    ------
    UnsupportedOperation
        If the step contains an operation not translated (function calls, for instance).
    """
    _check_step(step, lookup)
    body = _lookup_lines(lookup) if lookup else []
    lines, used = instruction_lines(step)
    return _loop_source(step, name, block, done_index, body + lines, used)


def _check_step(step: ca.Function, lookup: dict | None) -> None:
    """The step must be an SX Function from one dense state to one of the same size (and the
    looked-up values second, with ``lookup``)."""
    if not step.is_a("SXFunction"):
        raise UnsupportedOperation("the step must be an SX Function")
    n_in = 2 if lookup else 1
    if step.n_in() != n_in or step.n_out() != 1 or step.nnz_in(0) != step.nnz_out(0):
        raise UnsupportedOperation("the step must map one dense state to one of the same size"
                                   + (" (and take the looked-up values second)" if lookup else ""))
    if lookup and step.nnz_in(1) != int(lookup["channels"]):
        raise UnsupportedOperation(f"the step's second input has {step.nnz_in(1)} entries, "
                                   f"the table {int(lookup['channels'])} channels")


def _lookup_lines(L: dict) -> list[str]:
    """C statements that read ``a0``, ``a1``, ... by bilinear interpolation from the table
    ``T`` at the state's grid coordinates (clamped to the grid's last cell, as CasADi)."""
    c = int(L["channels"])
    body = []
    for ax, (si, o, d, nn) in (("x", (L["ix"], L["x0"], L["dx"], L["nx"])),
                               ("y", (L["iy"], L["y0"], L["dy"], L["ny"]))):
        body += [f"double g{ax} = (S[{int(si)} * stride + i] - {float(o)!r}) / {float(d)!r};",
                 f"double c{ax} = floor(g{ax});",
                 f"c{ax} = c{ax} < 0.0 ? 0.0 : (c{ax} > {int(nn) - 2}.0 ? "
                 f"{int(nn) - 2}.0 : c{ax});",
                 f"double f{ax} = g{ax} - c{ax};"]
    nx = int(L["nx"])
    body.append(f"int k00 = {c} * ((int)cx + {nx} * (int)cy);")
    offs = {"00": "k00", "10": f"k00 + {c}", "01": f"k00 + {c * nx}",
            "11": f"k00 + {c * (nx + 1)}"}
    for j in range(c):
        body.append(
            f"double a{j} = (1.0 - fx) * (1.0 - fy) * T[{offs['00']} + {j}] "
            f"+ fx * (1.0 - fy) * T[{offs['10']} + {j}] "
            f"+ (1.0 - fx) * fy * T[{offs['01']} + {j}] + fx * fy * T[{offs['11']} + {j}];")
    return body


def _step_read(arg: int, nz: int) -> str:
    """A step's inputs in C: the state ``S`` (column ``i``), then the looked-up values ``a``."""
    return f"a{nz}" if arg == 1 else f"S[{nz} * stride + i]"


def _step_write(res: int, nz: int) -> str:
    return f"o{nz}"


def instruction_lines(step: ca.Function, read=_step_read, write=_step_write
                       ) -> tuple[list[str], set[str]]:
    """One C statement per instruction of the SX Function (work variables ``w``), and the
    vector math functions they call. ``read(arg, nz)`` and ``write(res, nz)`` give the C
    expressions of input ``arg``'s and output ``res``'s entry ``nz``."""
    body: list[str] = []
    used: set[str] = set()
    for k in range(step.n_instructions()):
        op = step.instruction_id(k)
        ins = step.instruction_input(k)
        out = step.instruction_output(k)
        if op == ca.OP_INPUT:
            body.append(f"w{out[0]} = {read(ins[0], ins[1])};")
        elif op == ca.OP_OUTPUT:
            body.append(f"{write(out[0], out[1])} = w{ins[0]};")
        elif op == ca.OP_CONST:
            c = float(step.instruction_constant(k))
            lit = repr(c) if np.isfinite(c) else ("NAN" if np.isnan(c) else
                                                  ("INFINITY" if c > 0 else "-INFINITY"))
            body.append(f"w{out[0]} = {lit};")
        elif op in _BINARY:
            body.append(f"w{out[0]} = " + _BINARY[op].format(f"w{ins[0]}", f"w{ins[1]}") + ";")
        elif op in _UNARY:
            body.append(f"w{out[0]} = " + _UNARY[op].format(f"w{ins[0]}") + ";")
        else:
            names = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}
            raise UnsupportedOperation(f"operation {names.get(op, op)} is not translated")
        used.update(f for f in VECTOR_MATH if f + "(" in body[-1])
    return body, used


def _loop_source(step: ca.Function, name: str, block: int, done_index: int | None,
                 body: list[str], used: set[str]) -> str:
    """The C function: blocks of states, ``steps`` steps each in an ``omp simd`` loop over the
    block, an early stop once the block is done (with ``done_index``)."""
    m = step.nnz_in(0)
    decl_w = ", ".join(f"w{j}" for j in range(step.sz_w()))
    decl_o = ", ".join(f"o{j}" for j in range(m))
    stores = " ".join(f"S[{j} * stride + i] = o{j};" for j in range(m))
    simd_decls = "\n".join(
        f"#pragma omp declare simd notinbranch\nextern double {f}(double"
        + (", double" if f in ("pow", "atan2") else "") + ");" for f in sorted(used))
    stop = ""
    if done_index is not None:
        stop = f"""
      if ((k & 7) == 7) {{
        int all_done = 1;
        for (int i = b; i < e; ++i) all_done &= (S[{int(done_index)} * stride + i] != 0.0);
        if (all_done) break;
      }}"""
    lines = "\n        ".join(body)
    return f"""/* generated by seds_casadi.simd from CasADi function {step.name()} */
#include <math.h>
{simd_decls}

void {name}(int n, int stride, int steps, double *restrict S, const double *restrict T) {{
  for (int b = 0; b < n; b += {int(block)}) {{
    int e = b + {int(block)} < n ? b + {int(block)} : n;
    for (int k = 0; k < steps; ++k) {{
      #pragma omp simd
      for (int i = b; i < e; ++i) {{
        double {decl_w};
        double {decl_o};
        {lines}
        {stores}
      }}{stop}
    }}
  }}
}}
"""


def load_library(path: str) -> ctypes.CDLL:
    """A compiled library, loaded once per process."""
    with _LOCK:
        lib = _LOADED.get(path)
        if lib is None:
            lib = _LOADED[path] = ctypes.CDLL(path)
        return lib


def cpu_key() -> str:
    """A short hash of the CPU's feature flags: the cache key of code compiled with
    ``-march=native`` (a library built for one CPU is not loaded on another)."""
    try:
        with open("/proc/cpuinfo") as fh:
            flags = next((ln for ln in fh if ln.startswith("flags")), "")
    except OSError:
        flags = ""
    return hashlib.sha256(flags.encode()).hexdigest()[:12]


class SimdLoop:
    """A step function compiled by :func:`simd_source` and loaded with ctypes.

    Parameters
    ----------
    step : casadi.Function
        SX step function, state in, state out.
    name : str
        C symbol name.
    done_index : int, optional
        State component that is non-zero once a state is finished (see :func:`simd_source`).
    threads : int
        Calls split the states over this many threads (ctypes releases the GIL).
    lookup, table : dict and array, optional
        A table read by linear interpolation into the step's second input (see
        :func:`simd_source`).

    Raises
    ------
    UnsupportedOperation
        Step not translatable.
    RuntimeError
        No C compiler, or compilation failed (the message has the compiler's output).
    """

    FLAGS = ("-O3", "-march=native", "-fopenmp-simd", "-fno-math-errno", "-fno-trapping-math")

    def __init__(self, step: ca.Function, name: str = "simd_step", done_index: int | None = None,
                 threads: int = 2, lookup: dict | None = None, table=None) -> None:
        src = simd_source(step, name, done_index, lookup=lookup)
        if lookup is not None:
            self._table = np.ascontiguousarray(table, dtype=np.float64).ravel()
            need = int(lookup["channels"]) * int(lookup["nx"]) * int(lookup["ny"])
            if self._table.size != need:
                raise ValueError(f"the table has {self._table.size} values, the lookup needs "
                                 f"{need}")
        else:
            self._table = np.zeros(1)
        self.n_state = step.nnz_in(0)
        self.threads = max(1, int(threads))
        libs = ("-lmvec", "-lm") if "declare simd" in src else ("-lm",)
        try:
            path = shared_library(src.encode(), "simd", self.FLAGS, libs, key_extra=cpu_key())
        except CompileError as exc:
            raise RuntimeError(f"compiling the SIMD loop failed: {exc}") from None
        fn = getattr(load_library(path), name)
        fn.restype = None
        fn.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int,
                       ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]
        self._fn = fn
        self.source = src
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None

    def run(self, S: np.ndarray, steps: int) -> None:
        """Advance the states in ``S`` (shape (n_state, n), C-contiguous float64) in place."""
        if S.dtype != np.float64 or not S.flags.c_contiguous or S.shape[0] != self.n_state:
            raise ValueError(f"S must be a C-contiguous float64 array of shape "
                             f"({self.n_state}, n)")
        n = S.shape[1]
        if n == 0 or steps <= 0:
            return
        base = S.ctypes.data
        table = self._table.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
        parts = self.threads if n >= 256 * self.threads else 1
        bounds = np.linspace(0, n, parts + 1).astype(int)
        # column blocks start at multiples of 8 so each thread's block is aligned alike
        bounds[1:-1] = (bounds[1:-1] // 8) * 8

        def call(lo: int, hi: int) -> None:
            ptr = ctypes.cast(base + 8 * lo, ctypes.POINTER(ctypes.c_double))
            self._fn(hi - lo, n, int(steps), ptr, table)

        if parts == 1:
            call(0, n)
            return
        futures = [self._pool.submit(call, int(a), int(b))
                   for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
        for f in futures:
            f.result()
