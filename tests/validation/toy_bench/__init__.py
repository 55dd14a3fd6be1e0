"""A bench kind written outside vissim, in one folder, to show what a new bench needs: this folder and one
registration line (`vissim.validation.engine.registry.register_bench_kind`)."""
