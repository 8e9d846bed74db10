"""File formats and image IO: each format one module with load_X / save_X."""
