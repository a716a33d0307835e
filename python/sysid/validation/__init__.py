"""Model validation: compare, residual whiteness, information criteria and order selection,
feedback tests."""
