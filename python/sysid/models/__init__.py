"""Model families (discrete and continuous state space) and model files (save/load)."""
