"""Subspace identification: SubspaceEstimator (n4sid, moesp, cva), closed-loop pbsid/ssarx,
frequency-domain subspace, recursive and streaming compression, orthogonal decomposition,
bootstrap."""
