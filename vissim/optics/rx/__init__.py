"""The prescription stage: what corrects the eye or camera, and how it views its object.

Spectacle prescriptions, refractive errors and power vectors (`prescription`); trial lenses in front
of a camera or an eye, their added power and magnification by ray-transfer matrices (`trial_lens`),
and their glass's dispersion (`glass`); the eye's accommodation (`accommodation`) and its
longitudinal chromatic aberration (`chromatic`); and the reduced eye's (or camera's) viewing setup:
what it focuses, through which pupil, with which magnification (`viewing_setup`). Importing this
package imports none of its modules.
"""
