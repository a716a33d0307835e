"""Analysis of data and models: validation, information criteria, modal analysis, model
reduction, non-parametric (spectral and correlation) estimates, LTI responses."""
