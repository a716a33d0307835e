"""MATLAB's order vectors: ``arx(data, [na nb nk])``, ``oe(data, [nb nf nk])``,
``armax(data, [na nb nc nk])``, ``bj(data, [nb nc nd nf nk])``, ``polyest(data, [na nb nc
nd nf nk])``, ``iv4``, ``arxregul``, ``nlarx`` and ``nlhw`` alike.

A MATLAB user's first call gives the orders as one vector (one row per output for several
outputs); the estimators here take them as separate arguments. :func:`matlab_orders` reads
the vector form when it is the only order argument given, and says what the vector should
hold when its length does not fit the data's channels.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError, ShapeError, not_a_record, refuse_frd

__all__ = ["matlab_orders"]

#: the order arguments of each estimator, in MATLAB's order, with how many numbers each takes
#: in one output's row: "1", one per input ("nu") or one per output ("ny")
LAYOUTS: dict[str, tuple[tuple[str, str], ...]] = {
    "arx": (("na", "ny"), ("nb", "nu"), ("nk", "nu")),
    "iv4": (("na", "ny"), ("nb", "nu"), ("nk", "nu")),
    "ivx": (("na", "ny"), ("nb", "nu"), ("nk", "nu")),
    "arxregul": (("na", "ny"), ("nb", "nu"), ("nk", "nu")),
    "armax": (("na", "1"), ("nb", "nu"), ("nc", "1"), ("nk", "nu")),
    "oe": (("nb", "nu"), ("nf", "nu"), ("nk", "nu")),
    "bj": (("nb", "nu"), ("nc", "1"), ("nd", "1"), ("nf", "nu"), ("nk", "nu")),
    "polyest": (("na", "1"), ("nb", "nu"), ("nc", "1"), ("nd", "1"), ("nf", "nu"),
                ("nk", "nu")),
    "nlhw": (("nb", "nu"), ("nf", "nu"), ("nk", "nu")),
    "nlarx": (("na", "ny"), ("nb", "nu"), ("nk", "nu")),
}

_WIDTH = {"1": "", "nu": " (one per input)", "ny": " (one per output)"}


def matlab_orders(fn: str, data: Any, first: Any, **rest: Any) -> tuple[Any, ...]:
    """The order arguments of estimator ``fn`` (``first``, then ``rest`` in its signature's
    order), read from MATLAB's vector form when ``first`` is a vector or matrix and no other
    order is given; otherwise as given, with a missing ``nk`` taken as 1.

    One output: a vector with the numbers of :data:`LAYOUTS` (``[na, nb_1 .. nb_nu, nk_1 ..
    nk_nu]`` for ``arx``); several outputs: one such row per output (``na`` then has one
    number per output in ``arx``, ``iv4`` and ``arxregul``: MATLAB's ``[NA NB NK]``).
    ``nlarx`` takes one vector, ``[na_1 .. na_ny, nb_1 .. nb_nu, nk_1 .. nk_nu]`` (its lags
    are shared by every output's equation).

    Examples
    --------
    >>> import numpy as np, sysid
    >>> d = sysid.IOData(u=np.zeros((50, 2)), y=np.zeros((50, 1)))
    >>> matlab_orders("arx", d, [2, 3, 1, 1, 2], nb=None, nk=None)
    (2, [3, 1], [1, 2])
    >>> matlab_orders("arx", d, 2, nb=3, nk=None)
    (2, 3, 1)
    """
    names = [k for k, _ in LAYOUTS[fn]]
    given = [first, *(rest[k] for k in names[1:])]
    if any(isinstance(v, str) for v in given):
        # order="auto" is the state-space estimators'; a polynomial model's orders are
        # chosen by comparing structures (MATLAB's arxstruc / selstruc), as here
        word = next(v for v in given if isinstance(v, str))
        raise DataError(
            f"{fn} takes its orders as whole numbers, got {word!r} (as MATLAB's {fn}, it has no "
            f"automatic order): compare structures with sysid.selstruc(sysid.arxstruc(est, "
            f"val, sysid.struc(range(1, 11), range(1, 11), nk))), or let a state-space fit "
            f"choose its order: sysid.ssest(data, 'auto') or sysid.identify(data)")
    # a time series has no input orders to give: arx(y, na), armax(y, na, nc=1) (MATLAB's
    # arx(data, na) for time series)
    series = getattr(data, "n_inputs", None) == 0
    per_input = {k for k, w in LAYOUTS[fn] if w == "nu"}
    missing = [k for k, v in zip(names[1:], given[1:])
               if v is None and k != "nk" and not (series and k in per_input)]
    stray = [k for k, v in zip(names[1:], given[1:])
             if series and k in per_input and v is not None and np.size(v)]
    if stray and not (np.ndim(first) > 0 and all(v is None for v in given[1:])):
        own = [k for k in names if k not in per_input]
        if not own or own == ["nc", "nd"]:  # oe, nlhw, bj: models of the inputs' response
            raise DataError(f"{fn} models the response to inputs, and the record has none (a "
                            "time series): use sysid.ar(data, na) or sysid.armax(data, [na, "
                            "nc])")
        raise DataError(
            f"the record has no inputs (a time series), so {fn} takes no {', '.join(stray)}: "
            f"{fn}(data, {', '.join(f'{k}=...' if i else k for i, k in enumerate(own))})"
            + (f", or [{', '.join(own)}] as in MATLAB" if len(own) > 1 else ""))
    try:
        vector = np.ndim(first) > 0 and not isinstance(first, str)
    except ValueError:  # a ragged sequence, [1, [1, 1], [1, 1]]: MATLAB's vector is flat
        raise DataError(f"{fn}'s orders as one vector are flat numbers "
                        f"({', '.join(names)} in turn, one per channel), got {first!r:.60}; "
                        f"or give them separately, {fn}(data, {', '.join(names)})") from None
    if not vector or any(v is not None for v in given[1:]):
        if missing:
            alone = " (the vector comes alone)" if vector else ""
            raise DataError(
                f"{fn} needs {', '.join(missing)}: {fn}(data, {', '.join(names)}), or the "
                f"orders as one vector, {fn}(data, [{', '.join(names)}]) as in MATLAB{alone}")
        return tuple([] if (series and k in per_input and v is None)
                     else 1 if (k == "nk" and v is None) else v for k, v in zip(names, given))
    if not hasattr(data, "n_inputs"):
        refuse_frd(data, fn)
        raise not_a_record(data)
    nu, ny = data.n_inputs, data.n_outputs
    widths = [{"1": 1, "nu": nu, "ny": ny}[w] for _, w in LAYOUTS[fn]]
    try:
        a = np.asarray(first, dtype=float)
    except (TypeError, ValueError):
        a = np.full(1, np.nan)
    one = ny == 1 or fn == "nlarx"  # one vector (nlarx: its lags serve every output)
    rows = a.reshape(1, -1) if a.ndim == 1 and one else a
    what = ", ".join(f"{k}{_WIDTH[w]}" for k, w in LAYOUTS[fn])
    if rows.ndim != 2 or rows.shape != (1 if one else ny, sum(widths)):
        form = (f"a vector of {sum(widths)} numbers" if one else
                f"{ny} rows (one per output) of {sum(widths)} numbers")
        raise ShapeError(
            f"{fn}'s orders as one vector are [{what}]: for {nu} input(s) and {ny} output(s) "
            f"{form}, got shape {np.shape(first)}; or give them separately, "
            f"{fn}(data, {', '.join(names)})")
    if not np.all(np.isfinite(rows)) or np.any(rows != np.round(rows)) or np.any(rows < 0):
        raise DataError(f"{fn}'s orders must be whole numbers >= 0, got {np.asarray(first)}")
    ints = rows.astype(int)
    out: list[Any] = []
    col = 0
    for (_, sym), w in zip(LAYOUTS[fn], widths):
        block = ints[:, col:col + w]
        col += w
        if one:  # one output: a number, or one per channel
            out.append(int(block[0, 0]) if w == 1 else block[0].tolist())
        else:  # one per output (armax's na, bj's nc, nd), else a grid (outputs x channels)
            out.append(block[:, 0].tolist() if sym == "1" else block.tolist())
    return tuple(out)
