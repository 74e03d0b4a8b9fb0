"""The wire: DBC codecs, ARS 408-21 frames, bus load, the node and its clocks."""
