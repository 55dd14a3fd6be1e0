"""`Eye`: the one object every eye simulation, render and campaign takes.

An `Eye` is a schematic model's surfaces and media (`SchematicEye`: any of the five models, one
altered, or one built by hand) at its accommodation, with

* the prescription it **has** (``rx``, a spectacle prescription measured ``vertex_distance_mm`` in front of
  the cornea): the eye is then the ametropic eye that needs it (`fixation.ametropic_eye`: axial
  length for the spherical equivalent, a toric cornea front for the cylinder). ``rx`` never means a
  defocus added to the emmetropic model: a lens worn in front is a lens, not part of the eye;
* its pupil, given once: the entrance pupil ``pupil_diameter_mm`` or the ``iris_mm`` (default:
  `DEFAULT_EYE_PUPIL_MM` of entrance pupil);
* its reference wavelength ``wavelength_nm`` (default: the model's): the light its prescription
  is measured in and the chief ray that is the image frame's origin.

It is immutable: altered with `dataclasses.replace` or the builders (`Eye.with_pupil`,
`Eye.with_rx`, `Eye.accommodated`, `Eye.with_surface`). `build_eye` makes one from a model's
name; entry points take an `Eye` and never a name, so a name is resolved once, at the edge.

Examples
--------
>>> from vissim.optics.eyes.eye import build_eye
>>> eye = build_eye("navarro-1985", pupil_diameter_mm=3.0, rx="-2.00")
>>> eye.model, eye.pupil_diameter_mm, str(eye.rx)
('navarro-1985', 3.0, '-2.00 DS')
>>> round(eye.optics.axial_length_mm - eye.schematic.axial_length_mm, 3)
0.751
>>> eye.with_surface("cornea front", conic=-0.5).schematic.surfaces[0].conic
-0.5
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
from dataclasses import dataclass, field

from vissim.checks import (eye_prescription_meridians, eye_pupil_diameter_mm, eye_wavelength_nm, instance_of,
                           positive_number)
from vissim.checks import vertex_distance_mm as checked_vertex_distance_mm
from vissim.errors import VissimInputError
from vissim.optics.eyes.fixation import ametropic_eye
from vissim.optics.eyes.defaults import DEFAULT_EYE_PUPIL_MM, DEFAULT_SPECTACLE_VERTEX_MM
from vissim.optics.eyes.measured.measured_eye import (BASE_EYE_MODEL, MeasuredWavefront, is_measured_name,
                                                      parse_measured_eye)
from vissim.optics.eyes.models import EYE_MODELS, SchematicEye, eye_model
from vissim.optics.eyes.traced_wavefront import pupils_mm
from vissim.optics.rx.prescription import Prescription, prescription_from

__all__ = ["Eye", "build_eye", "eye_from_fields", "SURFACE_OVERRIDES", "checked_eye", "surface_overrides",
           "overrides_table"]

#: The `EyeSurface` fields `Eye.with_surface` may change, with their units.
SURFACE_OVERRIDES = {"radius_mm": "mm", "conic": "", "thickness_after_mm": "mm", "radius_y_mm": "mm",
                     "axis_deg": "deg"}


@dataclass(frozen=True)
class Eye:
    """An eye to simulate or render (module doc). Build one with `build_eye`."""

    schematic: SchematicEye
    pupil_diameter_mm: float | None = None
    iris_mm: float | None = None
    rx: Prescription | None = None
    vertex_distance_mm: float = DEFAULT_SPECTACLE_VERTEX_MM
    wavelength_nm: float | None = None
    measured: MeasuredWavefront | None = None
    _optics: SchematicEye = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        instance_of(self.schematic, SchematicEye, "an Eye's schematic", "a SchematicEye (vissim.optics.eyes.models)")
        if self.pupil_diameter_mm is not None and self.iris_mm is not None:
            raise VissimInputError(f"give the eye's entrance pupil ({self.pupil_diameter_mm!r} mm) or its iris "
                                   f"({self.iris_mm!r} mm), not both")
        if self.iris_mm is not None:
            object.__setattr__(self, "iris_mm", positive_number(self.iris_mm, "iris diameter", "mm"))
        else:
            pupil = DEFAULT_EYE_PUPIL_MM if self.pupil_diameter_mm is None else self.pupil_diameter_mm
            # a human eye's (`EYE_PUPIL_RANGE_MM`), for every command and file that builds an eye; a bare trace
            # (`trace_eye_wavefront`) takes any pupil, for the physics of its limits
            object.__setattr__(self, "pupil_diameter_mm", eye_pupil_diameter_mm(pupil, "entrance pupil diameter"))
        object.__setattr__(self, "vertex_distance_mm", checked_vertex_distance_mm(self.vertex_distance_mm, "spectacle vertex distance"))
        if self.wavelength_nm is not None:
            object.__setattr__(self, "wavelength_nm", eye_wavelength_nm(self.wavelength_nm,
                                                                        "eye's reference wavelength"))
        if self.rx is not None:
            object.__setattr__(self, "rx", prescription_from(self.rx))
            self._check_rx_range()
        if self.measured is not None:
            self._check_measured()
        object.__setattr__(self, "_optics", self._traced_optics())  # a prescription the eye cannot have: refused now
        if self.measured is None:  # a pupil or iris no trace of this eye takes: refused now, not inside a render
            pupils_mm(self._optics, self.reference_wavelength_nm, self.pupil_diameter_mm if self.iris_mm is None else None,
                      self.iris_mm)

    def _check_rx_range(self) -> None:
        """The prescription an eye is made to need lies, in each principal meridian, within the trial lenses'
        range (the lenses that would correct it): checked before its eye is built."""
        eye_prescription_meridians(self.rx.sphere_diopters, self.rx.cylinder_diopters,
                                   f"the prescription {self.rx} an eye is made to need")

    def _check_measured(self) -> None:
        instance_of(self.measured, MeasuredWavefront, "an Eye's measured wavefront", "a MeasuredWavefront")
        name = self.measured.name
        if self.rx is not None:
            raise VissimInputError(f"{name} is a measured eye with its own refraction; it cannot be given a "
                                   f"prescription ({self.rx}): put a lens in front, or correct it in the light")
        if self.schematic != eye_model(BASE_EYE_MODEL):
            raise VissimInputError(f"{name} is built on the relaxed {BASE_EYE_MODEL} eye as published: its surfaces, "
                                   "accommodation and model cannot change")
        if self.pupil_diameter_mm is not None:
            self.measured.checked_pupil_mm(self.pupil_diameter_mm)

    def _traced_optics(self) -> SchematicEye:
        optics = self._in_own_light(self.schematic)
        if self.rx is None:
            return optics
        if optics.accommodation_diopters == 0.0:
            return ametropic_eye(optics, self.rx, self.vertex_distance_mm)
        return self._accommodating_ametrope(optics)

    def _in_own_light(self, schematic: SchematicEye) -> SchematicEye:
        if self.wavelength_nm is None or self.wavelength_nm == schematic.reference_wavelength_nm:
            return schematic
        return dataclasses.replace(schematic, reference_wavelength_nm=self.wavelength_nm)

    def _accommodating_ametrope(self, optics: SchematicEye) -> SchematicEye:
        """A prescription is the relaxed eye's: the relaxed model is made to have it (its length, its cornea), then
        accommodates as the model's formulas say (lens and chamber; the vitreous by the model's own change)."""
        if self.schematic != _named_schematic(self.schematic):
            raise VissimInputError(f"the {self.model} eye accommodates {self.accommodation_diopters:g} D and has "
                                   f"{self.rx}: its prescription is the relaxed eye's, solved on the relaxed model, "
                                   "so it must be a named model with its surfaces unaltered")
        relaxed = self._in_own_light(eye_model(self.model, 0.0))
        solved = ametropic_eye(relaxed, self.rx, self.vertex_distance_mm)
        model_change_mm = optics.surfaces[-2].thickness_after_mm - relaxed.surfaces[-2].thickness_after_mm
        surfaces = list(optics.surfaces)
        surfaces[0] = solved.surfaces[0]
        surfaces[-2] = dataclasses.replace(surfaces[-2], thickness_after_mm=solved.surfaces[-2].thickness_after_mm
                                           + model_change_mm)
        return dataclasses.replace(optics, surfaces=tuple(surfaces),
                                   source=f"{solved.source}; accommodated {self.accommodation_diopters:g} D")

    # -- what it is ----------------------------------------------------------------------
    @property
    def optics(self) -> SchematicEye:
        """The surfaces traced: the schematic eye made to need ``rx`` (itself when ``rx`` is None)."""
        return self._optics

    @property
    def model(self) -> str:
        """The eye's name: the schematic model's, or a measured eye's (``jaeken-artal-2012:17:right``)."""
        return self.schematic.name if self.measured is None else self.measured.name

    @property
    def accommodation_diopters(self) -> float:
        return self.schematic.accommodation_diopters

    @property
    def reference_wavelength_nm(self) -> float:
        """The eye's reference wavelength, nm: ``wavelength_nm``, else the model's."""
        return self.optics.reference_wavelength_nm

    @property
    def pupil(self) -> dict:
        """The pupil as the traces take it: ``{"pupil_mm": d}`` or ``{"iris_mm": d}``."""
        return {"iris_mm": self.iris_mm} if self.iris_mm is not None else {"pupil_mm": self.pupil_diameter_mm}

    def describe(self) -> str:
        """One line: model, accommodation, pupil, prescription."""
        pupil = f"iris {self.iris_mm:g} mm" if self.iris_mm is not None else f"entrance pupil {self.pupil_diameter_mm:g} mm"
        rx = "" if self.rx is None else f", has {self.rx} at {self.vertex_distance_mm:g} mm"
        return f"{self.model}, accommodation {self.accommodation_diopters:g} D, {pupil}{rx}"

    def as_json(self) -> dict:
        base = {} if self.measured is None else {"base_model": self.schematic.name}
        return {"model": self.model, **base, "accommodation_diopters": self.accommodation_diopters,
                "entrance_pupil_mm": self.pupil_diameter_mm, "iris_mm": self.iris_mm,
                "rx": None if self.rx is None else self.rx.format(6), "vertex_mm": self.vertex_distance_mm,
                "reference_wavelength_nm": self.reference_wavelength_nm}

    # -- builders ------------------------------------------------------------------------
    def with_pupil(self, pupil_diameter_mm: float | None = None, iris_mm: float | None = None) -> Eye:
        """The same eye with its entrance pupil or its iris (one of them) set."""
        return dataclasses.replace(self, pupil_diameter_mm=pupil_diameter_mm, iris_mm=iris_mm)

    def with_assumed_pupil(self, pupil_diameter_mm: float) -> Eye:
        """The same eye with an entrance pupil a simulation assumes (its iris taken for the pupil, say): any
        positive diameter, where an eye one builds holds to a human eye's `EYE_PUPIL_RANGE_MM`."""
        eye = copy.copy(self)  # the optics do not depend on the pupil: nothing to rebuild
        object.__setattr__(eye, "pupil_diameter_mm", positive_number(pupil_diameter_mm, "assumed entrance pupil", "mm"))
        object.__setattr__(eye, "iris_mm", None)
        return eye

    def with_rx(self, rx, vertex_distance_mm: float | None = None) -> Eye:
        """The same eye made to have ``rx`` (None: emmetropic), measured ``vertex_distance_mm`` in front (default:
        its own)."""
        return dataclasses.replace(self, rx=rx, vertex_distance_mm=self.vertex_distance_mm if vertex_distance_mm is None
                                   else vertex_distance_mm)

    def accommodated(self, accommodation_diopters: float) -> Eye:
        """The same eye accommodating ``accommodation_diopters``: its model rebuilt (refused for an eye whose
        surfaces were altered or built by hand, which have no accommodation formulas)."""
        if self.schematic != _named_schematic(self.schematic):
            raise VissimInputError(f"the {self.model} eye's surfaces were altered or built by hand: accommodate its "
                                   "model first (build_eye(..., accommodation_diopters=A)), then alter it")
        return dataclasses.replace(self, schematic=eye_model(self.model, accommodation_diopters))

    def with_surface(self, surface: str, **changes) -> Eye:
        """The same eye with one surface (by name, e.g. ``"cornea front"``) changed: any of `SURFACE_OVERRIDES`."""
        return dataclasses.replace(self, schematic=altered_schematic(self.schematic, surface, changes))


def _named_schematic(schematic: SchematicEye) -> SchematicEye | None:
    if schematic.name not in EYE_MODELS:
        return None
    return eye_model(schematic.name, schematic.accommodation_diopters)


def altered_schematic(schematic: SchematicEye, surface: str, changes: dict) -> SchematicEye:
    """``schematic`` with the surface named ``surface`` changed by ``changes`` (fields of `SURFACE_OVERRIDES`)."""
    names = [s.name for s in schematic.surfaces]
    if surface not in names:
        raise VissimInputError(f"the {schematic.name} eye has no surface {surface!r}; its surfaces: {', '.join(names)}")
    values = {}
    for key, value in changes.items():
        if key not in SURFACE_OVERRIDES:
            raise VissimInputError(f"cannot change a surface's {key!r}; the fields that can change: "
                                   f"{', '.join(SURFACE_OVERRIDES)}")
        values[key] = _surface_value(key, value, surface)
    index = names.index(surface)
    surfaces = list(schematic.surfaces)
    surfaces[index] = dataclasses.replace(surfaces[index], **values)
    said = ", ".join(f"{key} {value:g}" for key, value in values.items())
    return dataclasses.replace(schematic, surfaces=tuple(surfaces), source=f"{schematic.source}; {surface}: {said}")


def _surface_value(key: str, value, surface: str) -> float:
    unit = SURFACE_OVERRIDES[key] or "(no unit)"
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if isinstance(value, bool) or not math.isfinite(number):
        raise VissimInputError(f"{surface} {key} must be a finite number {unit}, got {value!r}")
    if key.startswith("radius") and number == 0:
        raise VissimInputError(f"{surface} {key} must be a non-zero number of mm, got {value!r}")
    if key == "thickness_after_mm" and number < 0.0:
        raise VissimInputError(f"{surface} thickness_after_mm must be >= 0 mm, got {number:g} mm")
    return number


def build_eye(model: str | SchematicEye, *, accommodation_diopters: float = 0.0, pupil_diameter_mm: float | None = None,
              iris_mm: float | None = None, rx=None, vertex_distance_mm: float = DEFAULT_SPECTACLE_VERTEX_MM,
              wavelength_nm: float | None = None, surfaces: dict | None = None) -> Eye:
    """The `Eye` of the schematic model ``model`` (a key of `EYE_MODELS`, a `SchematicEye` built by hand, or a
    measured eye's name: `vissim.optics.eyes.measured.measured_eye`)
    at ``accommodation_diopters``, with its pupil, the prescription it has, its reference wavelength and
    ``surfaces`` overrides ({surface name: {field: value}}, `SURFACE_OVERRIDES`). The one place a model's name
    becomes an eye."""
    if is_measured_name(model):
        return _measured_eye(parse_measured_eye(model), accommodation_diopters, pupil_diameter_mm, iris_mm, rx,
                             vertex_distance_mm,
                             wavelength_nm, surfaces)
    if isinstance(model, SchematicEye):
        if accommodation_diopters:
            raise VissimInputError("a SchematicEye built by hand has its own accommodation; accommodation_diopters "
                                   f"must be 0 D, got {accommodation_diopters!r} D")
        schematic = model
    else:
        schematic = eye_model(model, accommodation_diopters)
    if surfaces is not None and not isinstance(surfaces, dict):
        raise VissimInputError(f"surfaces must be a table {{surface name: {{field: value}}}}, got {surfaces!r}")
    for surface, changes in (surfaces or {}).items():
        if not isinstance(changes, dict):
            raise VissimInputError(f"surface {surface!r}'s changes must be a table of fields, got {changes!r}")
        schematic = altered_schematic(schematic, surface, changes)
    return Eye(schematic, pupil_diameter_mm, iris_mm, rx, vertex_distance_mm, wavelength_nm)


def _measured_eye(measured: MeasuredWavefront, accommodation_diopters, pupil_diameter_mm, iris_mm, rx, vertex_distance_mm,
                  wavelength_nm, surfaces) -> Eye:
    """A measured eye (`vissim.optics.eyes.measured.measured_eye`) on its base eye, relaxed and unaltered."""
    if accommodation_diopters:
        raise VissimInputError(f"{measured.name} is a measured eye, measured relaxed: its accommodation is 0 D only, "
                               f"got {accommodation_diopters!r} D")
    if surfaces:
        raise VissimInputError(f"{measured.name} is a measured eye: its base eye's surfaces cannot change")
    if rx is not None and not any(prescription_from(rx).power_vector()):
        rx = None  # plano: the eye as measured (blur-depth's --rx 0)
    return Eye(eye_model(BASE_EYE_MODEL), pupil_diameter_mm, iris_mm, rx, vertex_distance_mm, wavelength_nm, measured)


def checked_eye(eye, where: str) -> Eye:
    """``eye`` if it is an `Eye`; a model's name is refused with how to make one."""
    if isinstance(eye, str):
        raise VissimInputError(f"{where} takes an Eye, not the name {eye!r}: build it once with "
                               f"vissim.build_eye({eye!r}, pupil_diameter_mm=..., rx=...)")
    return instance_of(eye, Eye, f"{where}'s eye", "an Eye (vissim.build_eye)")


def surface_overrides(schematic: SchematicEye) -> tuple:
    """How ``schematic`` differs from its named model at its accommodation: sorted (surface, field, value)
    triples of `SURFACE_OVERRIDES` (empty for the model itself); any other difference is refused."""
    named = _named_schematic(schematic)
    if named is None or len(named.surfaces) != len(schematic.surfaces):
        raise VissimInputError(f"the {schematic.name} eye is not a named model with altered surfaces; only such "
                               "an eye can be written as a model and its changes")
    changes = []
    for mine, theirs in zip(schematic.surfaces, named.surfaces):
        for key in SURFACE_OVERRIDES:
            if getattr(mine, key) != getattr(theirs, key):
                changes.append((mine.name, key, getattr(mine, key)))
        rest = {k: v for k, v in dataclasses.asdict(mine).items() if k not in SURFACE_OVERRIDES}
        if mine.name != theirs.name or rest != {k: v for k, v in dataclasses.asdict(theirs).items()
                                                  if k not in SURFACE_OVERRIDES}:
            raise VissimInputError(f"the {schematic.name} eye's {mine.name} differs from its model's in more than "
                                   f"{', '.join(SURFACE_OVERRIDES)}")
    if dataclasses.replace(schematic, surfaces=named.surfaces, source=named.source) != named:
        raise VissimInputError(f"the {schematic.name} eye differs from its model beyond its surfaces")
    return tuple(sorted(changes))


def overrides_table(triples) -> dict:
    """(surface, field, value) triples as `build_eye`'s ``surfaces`` table."""
    table: dict = {}
    for surface, key, value in triples:
        table.setdefault(surface, {})[key] = value
    return table


def eye_from_fields(model: str, accommodation_diopters: float, pupil_diameter_mm, iris_mm, rx, vertex_distance_mm: float,
                    surfaces: tuple = ()) -> Eye:
    """`build_eye` of plain, hashable fields (``rx`` a `Prescription` or its text; ``surfaces``: (surface, field,
    value) triples), built once per distinct set in a process: a campaign item's eye and its render's are one
    object, whichever form their prescription came in."""
    return _cached_eye(model, accommodation_diopters, pupil_diameter_mm, iris_mm,
                       None if rx is None else prescription_from(rx), vertex_distance_mm, tuple(surfaces))


@functools.lru_cache(maxsize=64)
def _cached_eye(model: str, accommodation_diopters: float, pupil_diameter_mm, iris_mm, rx, vertex_distance_mm: float,
                surfaces: tuple) -> Eye:
    return build_eye(model, accommodation_diopters=accommodation_diopters, pupil_diameter_mm=pupil_diameter_mm, iris_mm=iris_mm,
                     rx=rx, vertex_distance_mm=vertex_distance_mm, surfaces=overrides_table(surfaces))


eye_from_fields.cache_clear = _cached_eye.cache_clear  # the cache is the builder's
