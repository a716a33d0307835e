"""Nonlinear state-space models: best linear approximation, PNLSS, neural state space."""
