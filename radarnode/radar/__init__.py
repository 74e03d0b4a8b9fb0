"""Radar configuration, presets and the radar models (object level for now)."""
