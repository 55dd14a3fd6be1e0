"""The validation harness: Fourier vs ray-traced vs RAW captures."""
