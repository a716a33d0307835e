"""Real measured records bundled with sysid (unmodified DaISy copies).

``dryer``: laboratory hair dryer, 1000 samples, input heater voltage, output air temperature,
dt = 0.08 s (DaISy 96-006; SLICOT's identification example).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["path", "load_dryer", "NAMES"]

_DIR = Path(__file__).parent / "_data"
NAMES = ("dryer",)


def path(name: str) -> str:
    """Filesystem path of a bundled record.

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.path("dryer").endswith("dryer.dat")
    True
    """
    if name not in NAMES:
        raise ValueError(f"unknown data set {name!r}; bundled: {', '.join(NAMES)}")
    return str(_DIR / f"{name}.dat")


def load_dryer():  # type: ignore[no-untyped-def]
    """The hair-dryer record as :class:`sysid.IOData` (u: heater voltage, y: temperature).

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_dryer()
    IOData: 1000 samples, 1 input, 1 output, dt = 0.08 s
    """
    import numpy as np

    from .iodata import IOData

    d = np.loadtxt(path("dryer"))
    return IOData(
        u=d[:, :1],
        y=d[:, 1:],
        dt=0.08,
        input_names=["heater voltage"],
        output_names=["air temperature"],
    )
