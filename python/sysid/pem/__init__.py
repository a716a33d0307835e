"""Prediction-error refinement of state-space models: pem and ssest."""
