"""Measured data: the :class:`~sysid.IOData` container, file readers, pre-processing,
input design and the bundled records (:mod:`sysid.datasets`)."""
