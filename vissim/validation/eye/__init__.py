"""The eye bench: a letter rendered through a schematic eye (and a trial lens), against vissim's simulations."""
