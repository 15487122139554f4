"""Fused multiply-add for compiled code: ``fma(a, b, c) = a·b + c`` with one rounding.

numba exposes no ``fma`` (``math.fma`` is Python 3.13+), and LLVM does not contract
``a * b + c`` without fast-math, so a sum written with ``*`` and ``+`` rounds twice. This
intrinsic emits LLVM's ``llvm.fma.f64``: a hardware FMA instruction where the CPU has one,
else libm's correctly rounded ``fma``; the result is the same IEEE 754 value either way.

The flight software's ECI→ECEF rotation uses it to keep the arithmetic of the BLAS matrix
product it replaced (OpenBLAS's ``dgemv`` kernel accumulates with fused multiply-adds,
last column first), so the flights are bit for bit those of the BLAS version, and no
longer depend on which BLAS kernel a machine dispatches.
"""

from __future__ import annotations

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


@intrinsic
def _fma(typingctx, a, b, c):
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        dbl = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [dbl], ir.FunctionType(dbl, [dbl, dbl, dbl]))
        return builder.call(fn, args)

    return sig, codegen


@njit(cache=True, error_model="numpy", inline="always")
def fma(a: float, b: float, c: float) -> float:
    """``a·b + c`` rounded once (IEEE 754 fusedMultiplyAdd)."""
    return _fma(float(a), float(b), float(c))
