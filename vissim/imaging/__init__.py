"""Image operators shared by the fit and the campaigns (above the physics, below the benches).

* `vissim.imaging.registration` -- sub-pixel registration of a capture onto a reference.
"""
