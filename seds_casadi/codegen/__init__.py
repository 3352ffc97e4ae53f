"""Code generation: CasADi Functions compiled to C and loaded back, a low-overhead numeric
evaluator, batched evaluation of point-wise Functions, the vectorised (SIMD) loop generated
from an SX step function and the vectorised sum of an SX function over many columns, all
through one compile-and-cache helper (:func:`~seds_casadi.codegen.cache.shared_library`).
The lowest layer: it imports only casadi and numpy, and every other layer may use it.
"""

from .cache import CompileError, cache_folder, compiler_available, shared_library
from .column_sum import ColumnSum
from .functions import CachedFunctionMixin, FastEvaluator, batch_evaluate, compile_functions
from .simd import SimdLoop, UnsupportedOperation, simd_source

__all__ = ["compile_functions", "FastEvaluator", "batch_evaluate", "CachedFunctionMixin",
           "compiler_available",
           "cache_folder", "shared_library", "CompileError", "SimdLoop", "ColumnSum",
           "UnsupportedOperation",
           "simd_source"]
