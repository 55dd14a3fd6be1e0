"""The depth bench (scenes of charts at several distances) as a bench kind of the validation engine
(`vissim.validation.depth.kind`)."""
