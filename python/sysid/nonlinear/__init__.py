"""Nonlinear black-box models: NARX (nlarx), Hammerstein-Wiener (nlhw, nlhw_ss), basis-
augmented linear models."""
