"""The eyes that scenes' ``vissim_schematic_eye`` sensors look through, handed over as objects.

A Mitsuba scene dict holds plain values, so the eye bench's scene names its `vissim.optics.eyes.eye.Eye`
by a key (`register_sensor_eye`) and the sensor (`vissim.render.schematic_eye_sensor`) takes the eye
itself back (`sensor_eye`): its surfaces and media, its pupil, never a name to build it from.  The keys
hold in the process that registered them (the one that loads the scene).
"""

from __future__ import annotations

from vissim.errors import VissimInputError

__all__ = ["register_sensor_eye", "sensor_eye"]

_EYES: dict = {}


def register_sensor_eye(eye) -> str:
    """Hand the `Eye` ``eye`` to the sensors of scenes loaded in this process; the key a scene names it by."""
    key = f"eye-{hash(eye.optics) & 0xFFFFFFFFFFFF:012x}-{eye.pupil}"
    _EYES[key] = eye
    return key


def sensor_eye(key: str):
    """The `Eye` registered under ``key`` (`register_sensor_eye`)."""
    if key not in _EYES:
        raise VissimInputError(f"no eye is registered for the schematic-eye sensor under {key!r}: hand it over with "
                               "register_sensor_eye(eye) before loading the scene")
    return _EYES[key]
