"""Motion capture from image sequences and mocap (thesis ch. 4)."""
