"""Per-cycle radar output types (object and cluster lists) shared by all stages."""
