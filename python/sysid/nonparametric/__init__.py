"""Non-parametric estimates: frequency responses (spa, etfe, welch_frf), spectra, coherence,
correlation."""
