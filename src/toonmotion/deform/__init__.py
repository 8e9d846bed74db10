"""Shape deformation: needle model, joint-area solve, depth layers (thesis 3.4-3.5)."""
