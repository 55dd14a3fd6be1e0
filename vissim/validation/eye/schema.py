"""The eye bench's campaign file: ``[campaign]`` settings, ``[[item]]`` configurations and ``[[sweep]]`` grids.

An item is one rendered view of a letter through an eye: ``eye_model`` (spelled as the command line's
``--eye-model``: a schematic model or a measured eye, ``jaeken-artal-2012:92:right``, rendered as its base
eye with a phase plane: `vissim.optics.eyes.measured.phase_plane`), ``pupil_diameter_mm`` (the entrance pupil),
``accommodation_diopters``, ``field_deg`` (the chart centre's field angle [x, y], OSA's frame as every vissim
field angle: x the examiner's right, y up; a number is [x, 0]), its light: ``wavelength_nm`` (one wavelength)
or ``spectrum = "photopic"``, an optional trial ``lens`` (a sphere in D, or {sphere_diopters,
cylinder_diopters, axis_deg}), an optional ``prescription`` (the eye made ametropic: the spectacle
prescription it needs at the campaign's ``vertex_distance_mm``, a text such as ``"-3.00"`` or
``"-2.00 -1.00 x 90"``, or a number: the sphere in D; `vissim.optics.eyes.fixation.ametropic_eye`; absent: the
model as it is), ``letter``, ``logmar``, ``chart_distance_m`` (the campaign's unless given), and ``surfaces``:
the model's surfaces altered, a table of surface names each with fields of
`vissim.optics.eyes.eye.SURFACE_OVERRIDES` (``surfaces."cornea front".conic = 0.0``: an eye built from a model
plus overrides).  A ``[[sweep]]`` table gives lists for any of them and makes one item per combination (its
``name`` a prefix).  Keys spell the scene files' names (`vissim.vocabulary`); the old spellings
(``pupil_mm``, ``accommodation``, ``field``, ``light``, ``rx``, ``vertex_mm``) are refused naming the new one.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.datasets import measured_eye_words
from vissim.optics.eyes.defaults import (DEFAULT_CHART_DISTANCE_M, DEFAULT_EYE_ARCMIN_PER_PX, DEFAULT_EYE_LIGHT_NM,
                                         DEFAULT_EYE_MODEL, DEFAULT_EYE_PUPIL_MM, DEFAULT_EYE_SIZE_PX, DEFAULT_LETTER,
                                         DEFAULT_LETTER_LOGMAR, DEFAULT_SPECTACLE_VERTEX_MM)
from vissim.optics.eyes.eye import SURFACE_OVERRIDES, eye_from_fields
from vissim.optics.rx.prescription import Prescription
from vissim.checks import (ACCOMMODATION_RANGE_DIOPTERS, ARCMIN_PER_PX_RANGE, EYE_BENCH_RAYS_ACROSS_RANGE,
                           EYE_BENCH_SIZE_RANGE_PX, EYE_PUPIL_RANGE_MM, MAX_FIELD_DEG,
                           EYE_LIGHT_RANGE_NM, LOGMAR_RANGE, MAX_SPP, OVERSAMPLE_RANGE,
                           VERTEX_DISTANCE_RANGE_MM, VIEWING_DISTANCE_RANGE_M)
from vissim.validation.engine.configurations import refuse_duplicate_names, sweep_combinations
from vissim.validation.engine.fields import (field_error, lens, name_text, number, refuse_unknown_keys,
                                             settings_kwargs, tables, text, whole_number)

__all__ = ["EyeSettings", "EyeConfiguration", "read_campaign"]

LIGHTS = ("photopic",)
ITEM_KEYS = ("name", "eye_model", "pupil_diameter_mm", "accommodation_diopters", "field_deg", "wavelength_nm",
             "spectrum", "lens", "prescription", "letter", "logmar", "surfaces", "chart_distance_m")


@dataclass(frozen=True)
class EyeSettings:
    """Campaign-wide settings: samples per pixel, the two seeds, the image, the chart, the simulations' grid."""

    spp: int = 256
    seeds: tuple[int, int] = (1, 2)
    size_px: tuple[int, int] = DEFAULT_EYE_SIZE_PX
    arcmin_per_px: float = DEFAULT_EYE_ARCMIN_PER_PX
    chart_distance_m: float = DEFAULT_CHART_DISTANCE_M
    vertex_distance_mm: float = DEFAULT_SPECTACLE_VERTEX_MM
    oversample: int = 2
    rays_across: int = 161


@dataclass(frozen=True)
class EyeConfiguration:
    """One item (module doc); ``wavelength_nm`` None for photopic light."""

    name: str
    model: str = DEFAULT_EYE_MODEL
    pupil_mm: float = DEFAULT_EYE_PUPIL_MM
    accommodation_diopters: float = 0.0
    field_deg: tuple[float, float] = (0.0, 0.0)
    spectrum: str = "mono"
    wavelength_nm: float | None = DEFAULT_EYE_LIGHT_NM
    lens: tuple[float, float, float] | None = None  # sphere D, cylinder D, axis deg
    rx: Prescription | None = None  # the eye's spectacle prescription at vertex_mm (a number); None: the model's eye
    letter: str = DEFAULT_LETTER
    logmar: float = DEFAULT_LETTER_LOGMAR
    surfaces: tuple = ()  # sorted (surface name, field, value) triples: the model's surfaces altered
    # copied from the settings (so each item's key holds what its renders depend on)
    size_px: tuple[int, int] = DEFAULT_EYE_SIZE_PX
    arcmin_per_px: float = DEFAULT_EYE_ARCMIN_PER_PX
    chart_distance_m: float = DEFAULT_CHART_DISTANCE_M
    vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM

    def as_json(self) -> dict:
        return asdict(self)

    def key_inputs(self) -> dict:
        record = self.as_json()
        record.pop("name")
        if record["rx"] is None:  # the model's own eye: the key it had before items could be ametropic
            record.pop("rx")
        if not record["surfaces"]:  # the model's own surfaces: the key it had before they could be altered
            record.pop("surfaces")
        return record

    def eye(self):
        """The `Eye` of this item: the model at its accommodation, its surfaces altered, its entrance pupil and
        the prescription it has at ``vertex_mm`` (built once per configuration)."""
        return eye_from_fields(self.model, self.accommodation_diopters, self.pupil_mm, None, self.rx, self.vertex_mm,
                               self.surfaces)


def _light(entry: dict, source: str, where: str) -> tuple[str, float | None]:
    """("photopic", None) for ``spectrum = "photopic"``, else ("mono", ``wavelength_nm``)."""
    if "spectrum" in entry:
        if "wavelength_nm" in entry:
            raise field_error(source, where, "give wavelength_nm (one wavelength) or spectrum, not both")
        if entry["spectrum"] not in LIGHTS:
            raise field_error(source, f"{where}.spectrum", f"choose from {', '.join(LIGHTS)}, got {entry['spectrum']!r}")
        return "photopic", None
    return "mono", number(entry.get("wavelength_nm", DEFAULT_EYE_LIGHT_NM), source, f"{where}.wavelength_nm", "nm",
                          lo=EYE_LIGHT_RANGE_NM[0], hi=EYE_LIGHT_RANGE_NM[1])


def _field(value, source: str, where: str) -> tuple[float, float]:
    values = [value, 0.0] if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    if not isinstance(values, list) or len(values) != 2:
        raise field_error(source, where, f"a field is degrees (x, a number) or [x, y], got {value!r}")
    return tuple(number(v, source, where, "deg", lo=-MAX_FIELD_DEG, hi=MAX_FIELD_DEG) for v in values)


def _rx(value, source: str, where: str) -> Prescription:
    """A prescription text (`Prescription.parse`) or a number (the sphere, D): the `Prescription` itself, exactly
    as given (the render and the simulations take the number, never its text)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return Prescription(number(value, source, where, "D"), 0.0, 180.0)
    try:
        return Prescription.parse(text(value, source, where))
    except VissimInputError as error:
        raise field_error(source, where, str(error)) from None


def _surfaces(value, source: str, where: str) -> tuple:
    """``surfaces`` as sorted (surface, field, value) triples; each value a number in its field's unit."""
    if not isinstance(value, dict) or not all(isinstance(v, dict) for v in value.values()):
        raise field_error(source, where, "give a table of surface names, each a table of fields, e.g. "
                                         f"surfaces.\"cornea front\".conic = 0.0, got {value!r}")
    triples = []
    for surface, fields in value.items():
        for key, number_value in fields.items():
            if key not in SURFACE_OVERRIDES:
                raise field_error(source, f"{where}.{surface}", f"cannot change a surface's {key!r}; the fields that "
                                                                f"can change: {', '.join(SURFACE_OVERRIDES)}")
            unit = SURFACE_OVERRIDES[key] or "(no unit)"
            triples.append((surface, key, number(number_value, source, f"{where}.{surface}.{key}", unit)))
    return tuple(sorted(triples))


def _configuration(entry: dict, settings: EyeSettings, source: str, where: str) -> EyeConfiguration:
    refuse_unknown_keys(entry, ITEM_KEYS, source, where)
    spectrum, wavelength = _light(entry, source, where)
    trial = lens(entry["lens"], source, f"{where}.lens") if "lens" in entry else None
    trial = None if trial is None or (trial.sphere_diopters, trial.cylinder_diopters) == (0.0, 0.0) else (
        trial.sphere_diopters, trial.cylinder_diopters, trial.axis_deg)
    configuration = EyeConfiguration(
        name=name_text(entry.get("name", where), source, f"{where}.name"),
        model=text(entry.get("eye_model", DEFAULT_EYE_MODEL), source, f"{where}.eye_model"),
        pupil_mm=number(entry.get("pupil_diameter_mm", DEFAULT_EYE_PUPIL_MM), source, f"{where}.pupil_diameter_mm", "mm", lo=EYE_PUPIL_RANGE_MM[0], hi=EYE_PUPIL_RANGE_MM[1]),
        accommodation_diopters=number(entry.get("accommodation_diopters", 0.0), source, f"{where}.accommodation_diopters", "D",
                                      lo=ACCOMMODATION_RANGE_DIOPTERS[0], hi=ACCOMMODATION_RANGE_DIOPTERS[1]),
        field_deg=_field(entry.get("field_deg", 0.0), source, f"{where}.field_deg"),
        spectrum=spectrum, wavelength_nm=wavelength, lens=trial,
        rx=_rx(entry["prescription"], source, f"{where}.prescription") if "prescription" in entry else None,
        surfaces=_surfaces(entry.get("surfaces", {}), source, f"{where}.surfaces"),
        letter=text(entry.get("letter", DEFAULT_LETTER), source, f"{where}.letter"),
        logmar=number(entry.get("logmar", DEFAULT_LETTER_LOGMAR), source, f"{where}.logmar", "logMAR", lo=LOGMAR_RANGE[0], hi=LOGMAR_RANGE[1]),
        size_px=settings.size_px, arcmin_per_px=settings.arcmin_per_px, chart_distance_m=number(entry.get("chart_distance_m", settings.chart_distance_m), source, f"{where}.chart_distance_m", "m", lo=VIEWING_DISTANCE_RANGE_M[0], hi=VIEWING_DISTANCE_RANGE_M[1]),
        vertex_mm=settings.vertex_distance_mm)
    try:  # the model's name and its own accommodation range; the altered and the ametropic eye's own checks
        configuration.eye()
    except VissimInputError as error:
        raise field_error(source, where, str(error)) from None
    if configuration.lens is not None and configuration.field_deg != (0.0, 0.0):
        raise field_error(source, where, "a trial lens is simulated on the line of sight only: give field = 0 "
                                         "with a lens")
    return configuration


def _words(value) -> str:
    """A swept value as plain words (a list as "10,0"), for a key `axis_phrase` does not know."""
    if isinstance(value, dict):
        return ", ".join(f"{k} {_words(v)}" for k, v in value.items())
    if isinstance(value, list):
        return ",".join(f"{v:g}" for v in value)
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def axis_phrase(key: str, value) -> str:
    """`_axis_phrase`, or the key and value as written where the value is of a wrong type (the configuration's
    own checks refuse it, naming the item, after the name is made)."""
    try:
        return _axis_phrase(key, value)
    except (TypeError, ValueError, VissimInputError):
        return f"{key} {value!r}"


def _axis_phrase(key: str, value) -> str:
    """One swept setting in words, as a configuration's name says it: ``3 mm pupil``, ``10° field``,
    ``photopic light``, ``trial lens +1.00 -1.00 x 180`` (minus cylinder), ``2 D accommodation``."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if key == "pupil_diameter_mm" and number:
        return f"{value:g} mm pupil"
    if key == "accommodation_diopters" and number:
        return f"{value:g} D accommodation"
    if key == "field_deg":
        x, y = (value if isinstance(value, list) and len(value) == 2 else [value, 0.0])
        if isinstance(x, (int, float)) and isinstance(y, (int, float)):
            if (x, y) == (0, 0):
                return "on axis"
            return f"{x:g}° field" if y == 0 else f"field {x:g}°, {y:g}° (x, y)"
    if key == "spectrum":
        return f"{value} light"
    if key == "wavelength_nm" and number:
        return f"{value:g} nm light"
    if key == "lens":
        if number and value == 0:
            return "no lens"
        return f"trial lens {lens(value, '', key).label()}"  # the loader's own reading, in minus cylinder
    if key == "prescription":
        return f"eye Rx {_rx(value, '', key).minus_cylinder().format()}"
    if key == "logmar" and number:
        return f"LogMAR {value:g}"
    if key == "letter":
        return f"letter {value}"
    if key == "chart_distance_m" and number:
        return f"chart at {value:g} m"
    if key == "eye_model":
        return measured_eye_words(value)
    return f"{key} {_words(value)}"


def _tokens(text: str) -> set[str]:
    return {t.strip(",;:()").lower() for t in text.split()} - {""}


def sweep_name(prefix: str, chosen: dict) -> str:
    """A sweep member's name: its settings in words (`axis_phrase`), after the sweep's name unless every word of that
    name is said by them already ("field" before "10° field" would read "field 10° field")."""
    said = ", ".join(axis_phrase(k, v) for k, v in chosen.items())
    if not prefix or _tokens(prefix) <= _tokens(said):
        return said
    return f"{prefix}, {said}" if said else prefix


def _sweep(entry: dict, index: int, source: str) -> list[dict]:
    where = f"sweep[{index}]"
    prefix = name_text(entry.get("name", where), source, f"{where}.name")
    axes = {k: _axis_values(k, v) for k, v in entry.items() if k != "name"}
    return [{"name": sweep_name(prefix, chosen), **chosen} for chosen in sweep_combinations(axes, source, where)]


def _axis_values(key: str, value) -> list:
    """A sweep field's values: its list, or the one value it gives (a field is a list of [x, y] pairs to sweep)."""
    if key == "field_deg":
        return value if isinstance(value, list) and value and isinstance(value[0], list) else [value]
    return value if isinstance(value, list) else [value]


def _settings(head: dict, source: str) -> EyeSettings:
    kwargs = settings_kwargs(head, EyeSettings, source, "campaign",
                             numbers={"arcmin_per_px": ("arcmin/px", *ARCMIN_PER_PX_RANGE),
                                      "chart_distance_m": ("m", *VIEWING_DISTANCE_RANGE_M),
                                      "vertex_distance_mm": ("mm", *VERTEX_DISTANCE_RANGE_MM)},
                             whole_numbers={"spp": ("samples per pixel", 1, MAX_SPP),
                                            "oversample": ("", *OVERSAMPLE_RANGE),
                                            "rays_across": ("rays", *EYE_BENCH_RAYS_ACROSS_RANGE)},
                             lists={}, texts=("name", "description", "kind"), read_elsewhere=("size_px",))
    if "size_px" in head:
        size = head["size_px"]
        if not isinstance(size, list) or len(size) != 2:
            raise field_error(source, "campaign.size_px", f"give [rows, columns], got {size!r}")
        low, high = EYE_BENCH_SIZE_RANGE_PX
        kwargs["size_px"] = tuple(whole_number(v, source, "campaign.size_px", "px", lo=low, hi=high) for v in size)
    return EyeSettings(**kwargs)


def read_campaign(doc: dict, head: dict, source: str) -> tuple[EyeSettings, tuple[EyeConfiguration, ...]]:
    """The settings and the configurations (items, then each sweep's combinations) of a campaign file."""
    settings = _settings(head, source)
    entries = [(t, f"item[{i}]") for i, t in enumerate(tables(doc, "item", source))]
    for i, sweep in enumerate(tables(doc, "sweep", source)):
        entries += [(t, f"sweep[{i}] {t['name']}") for t in _sweep(sweep, i, source)]
    if not entries:
        raise field_error(source, "[[item]]", "the campaign has no items: add [[item]] or [[sweep]] tables")
    configurations = tuple(_configuration(t, settings, source, where) for t, where in entries)
    refuse_duplicate_names(source, [(where, c) for (_, where), c in zip(entries, configurations)], _describe,
                           hint="give each its own name")
    return settings, configurations


def _describe(c: EyeConfiguration) -> str:
    """What an item compares, for messages: the eye, its pupil, accommodation, field, light and lens."""
    light = "photopic" if c.wavelength_nm is None else f"{c.wavelength_nm:g} nm"
    lens = "no lens" if c.lens is None else f"trial lens {Prescription(*c.lens).minus_cylinder().format()}"
    return (f"{c.model}{'' if c.rx is None else f' Rx {c.rx}'}, pupil {c.pupil_mm:g} mm, "
            f"accommodation {c.accommodation_diopters:g} D, field {c.field_deg[0]:g},{c.field_deg[1]:g} deg, {light}, {lens}")
