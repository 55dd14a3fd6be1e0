"""The eyes that scenes' ``vissim_schematic_eye`` sensors look through, handed over as objects.

A Mitsuba scene dict holds plain values, so the eye bench's scene names its `vissim.optics.eyes.eye.Eye`
by a key (`register_sensor_eye`) and the sensor (`vissim.render.schematic_eye_sensor`) takes the eye
itself back (`sensor_eye`): its surfaces and media, its pupil, never a name to build it from; a measured eye's
phase plane travels with it (`sensor_phase`).  The keys
hold in the process that registered them (the one that loads the scene).
"""

from __future__ import annotations

from vissim.errors import VissimInputError

__all__ = ["register_sensor_eye", "sensor_eye", "sensor_phase"]

_EYES: dict = {}


def register_sensor_eye(eye, phase=None) -> str:
    """Hand the `Eye` ``eye`` to the sensors of scenes loaded in this process, with its phase plane ``phase`` (a
    measured eye's `vissim.optics.raytrace.phase.PhasePlane`; None: none); the key a scene names them by."""
    plane = "" if phase is None else f"-{hash(phase) & 0xFFFFFFFFFFFF:012x}"
    key = f"eye-{hash(eye.optics) & 0xFFFFFFFFFFFF:012x}-{eye.pupil}{plane}"
    _EYES[key] = (eye, phase)
    return key


def _registered(key: str):
    if key not in _EYES:
        raise VissimInputError(f"no eye is registered for the schematic-eye sensor under {key!r}: hand it over with "
                               "register_sensor_eye(eye) before loading the scene")
    return _EYES[key]


def sensor_eye(key: str):
    """The `Eye` registered under ``key`` (`register_sensor_eye`)."""
    return _registered(key)[0]


def sensor_phase(key: str):
    """The phase plane registered with the eye under ``key`` (None: none)."""
    return _registered(key)[1]
