"""Rasterising: overview pictures of a rig."""
