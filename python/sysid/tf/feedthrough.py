"""The one-sample lag of ``tfest``'s default structures against the record's direct term."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["WORDS", "lag_check", "say_discrete"]


def lag_check(data: Any, npo: np.ndarray, nze: np.ndarray, dt: float | None, ft: bool,
               iodelay: Any) -> dict[str, Any] | None:
    """The polynomial estimators' check of a one-sample lag against the record's direct term
    (:func:`sysid.polynomial.feedthrough.check_polynomial_feedthrough`), for the structures
    that have that lag: discrete without ``feedthrough``, continuous with fewer zeros than
    poles in every channel; none with ``iodelay`` given (a delay chosen). Returns the check's
    record for ``info["feedthrough_check"]`` or None.

    Examples
    --------
    >>> import numpy as np, sysid, warnings
    >>> from sysid.tf.feedthrough import lag_check
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((800, 1)); y = np.zeros((800, 1))
    >>> for t in range(1, 800): y[t] = 0.8 * y[t - 1] + u[t - 1] + 0.7 * u[t]
    >>> d = sysid.IOData(u, y + 0.05 * rng.standard_normal((800, 1)), 1.0)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     check = lag_check(d, np.array([[1]]), np.array([[0]]), 1.0, False, None)
    >>> [type(x.message).__name__ for x in w], check["ratio"] > 2
    (['FeedthroughWarning'], True)
    """
    if iodelay is not None or ft or (dt is None and np.any(nze >= npo)):
        return None
    from .._checks import experiment_arrays
    from ..polynomial.feedthrough import check_polynomial_feedthrough

    l, m = data.n_outputs, data.n_inputs
    return check_polynomial_feedthrough(
        experiment_arrays(data), "tfest", [int(np.max(npo[i])) for i in range(l)],
        [[1] * m for _ in range(l)], [[1] * m for _ in range(l)], data,
        **WORDS[dt is not None])


#: how the warning names each structure's one-sample lag and its way out (discrete: True)
WORDS = {True: {"lag": "(discrete, feedthrough=False) delays every input by one sample",
                "remedy": "Fit feedthrough=True"},
         False: {"lag": "(fewer zeros than poles) cannot answer within the sample",
                 "remedy": "Fit n_zeros equal to n_poles"}}


def say_discrete(check: dict[str, Any] | None) -> None:
    """What the ``oe`` fit of a discrete ``tfest`` found of the record's direct term
    (its ``info["feedthrough_check"]``), said in ``tfest``'s words: the check is made once,
    by that ``oe``."""
    from ..polynomial.feedthrough import say_left_out

    say_left_out(check, "tfest", **WORDS[True])
