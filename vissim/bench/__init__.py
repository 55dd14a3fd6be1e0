"""Scene builders for the virtual optical bench: plain dicts and meshes, no Mitsuba import."""
