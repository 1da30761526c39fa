"""How the planner's numba kernels are compiled: ``kernel`` for a function called from Python,
``inner`` for one only other kernels call (imported by the kernel modules alone: importing this
loads numba).

numba gives every compiled function two wrappers besides its code: one converting Python
objects to its arguments and back (for records of arrays and lists, the largest code of a
small function) and one for passing it as a first-class function value. Each is lowered,
optimised and turned into machine code with the function, and carried into every kernel it is
linked into. The kernels never pass functions as values, and an ``inner`` function is never
called from Python, so neither gets the wrappers it does not use: a fifth less compiling for
the first plan (dataset 2, turns, three objectives: 34.5 to 28.2 s of CPU in numba).
Both are cached (``cache=True``) as before. An ``inner`` function called from Python raises
numba's "no CPython wrapper" error; tests reach one through a kernel of their own.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from numba import njit

F = TypeVar("F", bound=Callable)


def kernel(fn: F) -> F:
    """Compile ``fn`` (cached), callable from Python and from other kernels."""
    return njit(cache=True, no_cfunc_wrapper=True)(fn)


def inner(fn: F) -> F:
    """Compile ``fn`` (cached), callable from other kernels only."""
    return njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)(fn)
