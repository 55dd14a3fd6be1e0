"""The DSLR bench of the thesis as a bench kind of the validation engine (`vissim.validation.dslr.kind`)."""
