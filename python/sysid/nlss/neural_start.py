"""Starts of :func:`sysid.nlssest` other than the plain linear model: a Hammerstein-Wiener
model embedded exactly in the neural state-space structure, and the parameter layout it
needs.

A Hammerstein-Wiener model ``w_j = f_j(u_j)``, ``x(t+1) = A x + B w``, ``v = C x + D w``,
``y_i = g_i(v_i)`` with sigmoid-network channels ``f(s) = c s + sum_k a_k tanh(b_k s + d_k)``
(or identities) is a neural state-space model with one tanh layer per network: ``B``'s
columns times ``c`` form the linear input term, each input unit ``tanh(b_k u_j + d_k)`` is a
hidden unit of the state network with output weights ``a_k B[:, j]``, and each output unit
``tanh(b_k (C_i x + D_i w) + d_k)`` a hidden unit of the output network (exact when ``D``
does not carry a nonlinear input channel: a unit of a unit needs a second layer). The
channel offsets and scales of the neural model go into the first layers' biases and the last
layers' biases; the remaining hidden units keep their random input weights and zero output
weights, free to learn what the block structure misses.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import DataError
from ..models.statespace import StateSpaceModel
from .common import Scaling


def layout(m: Any) -> dict[str, Any]:
    """Views into ``m.params`` (a :class:`NeuralStateSpaceModel`): ``A, B, C, D`` and the
    networks ``f``, ``g`` (``None`` without an output network), ``h`` as lists of layers
    ``(W, b)`` (``h`` also ``"skip"``, its linear term)."""
    n, mi, l_ = m.nstates, m.ninputs, m.noutputs
    p, k = m.params, 0

    def take(r: int, c: int) -> np.ndarray:
        nonlocal k
        v = p[k:k + r * c].reshape(r, c)
        k += r * c
        return v

    out: dict[str, Any] = {key: take(r, c) for key, r, c in
                           (("A", n, n), ("B", n, mi), ("C", l_, n), ("D", l_, mi))}

    def net(nin: int, hidden: tuple[int, ...], nout: int) -> list[tuple[Any, Any]]:
        sizes = [nin, *hidden, nout]
        return [(take(b, a), take(b, 1)[:, 0]) for a, b in zip(sizes[:-1], sizes[1:])]

    out["f"] = net(n + mi, m.hidden, n)
    out["g"] = None if m.output_hidden is None else net(n + mi, m.output_hidden, l_)
    nin = m.lags * (mi + l_)
    out["skip"] = take(n, nin)
    out["h"] = net(nin, m.encoder_hidden, n)
    return out


def _units(nl: Any, what: str) -> tuple[float, np.ndarray]:
    """A channel ``c s + sum_k a_k tanh(b_k s + d_k)`` as ``c`` and rows ``(a, b, d)``."""
    from ..nonlinear.hw_model import Nonlinearity, SigmoidNetwork

    if type(nl) is Nonlinearity:
        return 1.0, np.zeros((0, 3))
    if isinstance(nl, SigmoidNetwork):
        return nl.table()
    raise DataError(f"{what} is {type(nl).__name__}: only SigmoidNetwork and identity "
                    "channels embed exactly in a neural state-space model; fit the "
                    "Hammerstein-Wiener start with sysid.SigmoidNetwork")


def hw_units(hw: Any) -> tuple[int, int]:
    """Hidden units a Hammerstein-Wiener model needs in the state and output networks."""
    return (sum(_units(f, "an input channel")[1].shape[0] for f in hw.input_nls),
            sum(_units(g, "an output channel")[1].shape[0] for g in hw.output_nls))


def check_hw(hw: Any, order: int, m: int, l_: int, hidden: tuple[int, ...],
             output_hidden: tuple[int, ...] | None) -> None:
    """Refuses a Hammerstein-Wiener start that the structure cannot reproduce exactly."""
    if (hw.order, hw.ninputs, hw.noutputs) != (order, m, l_):
        raise DataError(f"init has {hw.order} states, {hw.ninputs} inputs and {hw.noutputs} "
                        f"outputs; the data and order need {order}, {m} and {l_}")
    nf, ng = hw_units(hw)
    if len(hidden) != 1 or hidden[0] < nf:
        raise DataError(f"a Hammerstein-Wiener start needs one hidden layer of at least {nf} "
                        f"units in the state network (its input units), got hidden={hidden}")
    if output_hidden is None or len(output_hidden) != 1 or output_hidden[0] < ng:
        raise DataError(f"a Hammerstein-Wiener start needs an output network of one hidden "
                        f"layer with at least {ng} units (its output units and offsets), got "
                        f"output_hidden={output_hidden}")
    for j, f in enumerate(hw.input_nls):
        if _units(f, "an input channel")[1].shape[0] and np.any(hw.D[:, j] != 0):
            raise DataError(f"input {j} has a nonlinearity and a direct term D: its units "
                            "inside the output units need two layers; fit the start without "
                            "feedthrough")


def embed_hw(start: Any, hw: Any, sc: Scaling) -> None:
    """Writes the Hammerstein-Wiener model ``hw`` (engineering units, checked by
    :func:`check_hw`) into ``start``'s linear part and first hidden units, in ``hw``'s state
    basis and ``sc``'s scaled channels; the other units keep zero output weights."""
    n = start.nstates
    su, mu = sc.u_scale, sc.u_offset
    sy, my = sc.y_scale, sc.y_offset
    v = layout(start)
    ins = [_units(f, "an input channel") for f in hw.input_nls]
    cin = np.array([c for c, _ in ins])
    A, B, C, D = hw.A, hw.B, hw.C, hw.D
    v["A"][:] = A
    v["B"][:] = B * (cin * su)
    (W1, b1), (W2, b2) = v["f"]
    b2[:] = B @ (cin * mu)
    r = 0
    for j, (_, U) in enumerate(ins):
        for a, b, d in U:
            W1[r] = 0.0
            W1[r, n + j] = b * su[j]
            b1[r] = b * mu[j] + d
            W2[:, r] = a * B[:, j]
            r += 1
    Dl, e = D * (cin * su), D @ (cin * mu)
    (G1, c1), (G2, c2) = v["g"]
    r = 0
    for i, g in enumerate(hw.output_nls):
        co, U = _units(g, "an output channel")
        v["C"][i] = co * C[i] / sy[i]
        v["D"][i] = co * Dl[i] / sy[i]
        c2[i] = (co * e[i] - my[i]) / sy[i]
        for a, b, d in U:
            G1[r, :n] = b * C[i]
            G1[r, n:] = b * Dl[i]
            c1[r] = b * e[i] + d
            G2[i, r] = a / sy[i]
            r += 1


def hw_states(hw: Any, sc: Scaling, us: list[np.ndarray]) -> list[np.ndarray]:
    """The states of ``hw`` from rest over scaled input records (its own basis)."""
    from .common import linear_states

    out = []
    for u in us:
        ue = u * sc.u_scale + sc.u_offset
        w = np.column_stack([f(ue[:, j]) for j, f in enumerate(hw.input_nls)])
        lin = StateSpaceModel(hw.A, hw.B, hw.C, hw.D, dt=hw.dt)
        out.append(linear_states(lin, [np.ascontiguousarray(w)])[0])
    return out
