"""The validation engine: one harness for every bench kind.

A campaign is configurations x truths x simulations x metrics.  The engine reads the campaign
file (`loader`), builds each configuration once through its bench kind (`protocol.BenchKind`,
found by name in `registry`), makes the renders the items need (`runner`, `renders`), computes
the items, and writes one report (`report`).  Keys (`keys`) name items and renders by their
inputs, so a re-run reuses what is done.
"""
