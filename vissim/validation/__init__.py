"""Validation: simulations scored against ground truths (renders, the wave bench, RAW captures).

`engine/` is the one harness (loader, keys, runner, report); `dslr/` and `depth/` are its bench
kinds, each registered by one line of `engine/registry.py`.
"""
