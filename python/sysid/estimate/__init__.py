"""Estimators: subspace identification, realisation from impulse responses, streaming
compression of long records."""
