"""Realisation: state-space models from Markov parameters (ho_kalman, kung, era) and Markov
parameters from data (impulse_response, okid)."""
