"""Polynomial models (ARX, ARMAX, OE, BJ, IV4, ARX with regularisation), structure and delay
selection."""
