"""Loaders turning recorded data into relloc's types (MRCLAM layout, UWB csv, ...)."""
