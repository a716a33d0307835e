"""Type stubs of the compiled core (``sysid._sysid``); see the Python wrappers for docs."""

from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str

Array = npt.NDArray[np.float64]

class HankelFactor:
    """Triangular factor L (k x k, H H^T = L L^T) of a block-Hankel data matrix."""

    @property
    def l(self) -> Array: ...
    @property
    def n_columns(self) -> int: ...
    @property
    def n_experiments(self) -> int: ...
    @property
    def n_inputs(self) -> int: ...
    @property
    def n_outputs(self) -> int: ...
    @property
    def past(self) -> int: ...
    @property
    def future(self) -> int: ...
    def merge(self, other: HankelFactor) -> HankelFactor: ...
    @staticmethod
    def from_parts(
        n_inputs: int,
        n_outputs: int,
        past: int,
        future: int,
        l: Array,
        n_columns: int,
        n_experiments: int,
    ) -> HankelFactor: ...
    def __reduce__(self) -> Any: ...

def compress(
    experiments: list[tuple[Array, Array]],
    past: int,
    future: int,
    chunk_rows: int | None = None,
) -> HankelFactor: ...

class Subspace:
    def __init__(self, factor: HankelFactor, method: str) -> None: ...
    @property
    def singular_values(self) -> Array: ...
    @property
    def max_order(self) -> int: ...
    def auto_order(self) -> int: ...
    def fit(self, order: int, feedthrough: bool, kalman: bool, stable: bool) -> dict[str, Any]: ...

def estimate_bd_x0(
    a: Array, c: Array, u: Array, y: Array, feedthrough: bool
) -> tuple[Array, Array, Array]: ...
def simulate(a: Array, b: Array, c: Array, d: Array, u: Array, x0: Array | None) -> Array: ...
def predict(
    a: Array,
    b: Array,
    c: Array,
    d: Array,
    k: Array,
    u: Array,
    y: Array,
    x0: Array | None,
    horizon: int,
) -> Array: ...
def kalman_gain(a: Array, c: Array, q: Array, r: Array, s: Array) -> tuple[Array, Array, Array]: ...
