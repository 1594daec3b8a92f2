"""BLAS threads for the analysis' small matrix products.

The products of the order choice, the view fits, the per-band statements and the lighting's
band sums are small (tens to a few hundred rows): a multithreaded BLAS spends more on waking and
spinning its threads than it saves, and on a busy machine its spinning threads take the cores
from everything else. Measured on this 2-core machine (load ≈ 5, ``shrm prefilter`` of
venice_sunset with microfacet σ = 0.1 at ε = 0.01): order choice 10.4 s with OpenBLAS's two
threads, 1.2 s with one; the lighting stage 4.3 s → 0.3 s. The large transforms run in ducc0,
whose threads are set by ``nthreads`` and are not affected.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

from threadpoolctl import threadpool_limits

__all__ = ["single_threaded_blas", "with_single_threaded_blas"]

_F = TypeVar("_F", bound=Callable[..., Any])


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Run the block with the BLAS libraries loaded in the process limited to one thread, and
    restore their limits afterwards (``threadpoolctl``)."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def with_single_threaded_blas(func: _F) -> _F:
    """Decorator: :func:`single_threaded_blas` around every call of ``func``."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with single_threaded_blas():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
