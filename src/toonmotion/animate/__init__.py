"""Key-frames, timelines and in-betweens (thesis 3.6, 6.3d)."""
