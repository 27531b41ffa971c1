"""Robot node processes over Zenoh (extra runtime)."""
