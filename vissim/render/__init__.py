"""The only package that imports Mitsuba 3 / Dr.Jit: variant choice, plugins, rendering, tracing."""
