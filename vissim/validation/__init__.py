"""Validation: simulations scored against ground truths (renders, the wave bench, RAW captures).

`engine/` is the one harness (loader, keys, runner, report, metrics); `dslr/`, `depth/` and `eye/`
are its bench kinds, each registered by one `register_bench_kind` line of `engine/registry.py`.
"""
