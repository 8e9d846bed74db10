"""Image to mask to silhouette to mesh; the curve skeleton."""
