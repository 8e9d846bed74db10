"""Skeleton, binding (decomposition) and the rigged Character."""
