"""Motion and measurement models only (no filter logic)."""
