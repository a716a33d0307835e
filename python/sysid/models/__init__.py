"""Model families (the layout helper owns this package; polynomial models live here)."""
