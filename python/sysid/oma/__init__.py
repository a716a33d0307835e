"""Output-only (operational) modal analysis: covariance- and data-driven stochastic subspace
identification with a stabilisation diagram (:func:`ssi`) and the modal assurance criterion
(:func:`mac`)."""

from .ssi import SSIResult, mac, ssi

__all__ = ["ssi", "SSIResult", "mac"]
