"""A population campaign file: the eyes in ``[campaign]``, and the conditions they are crossed with.

``kind = "population"``; ``dataset`` (``jaeken-artal-2012`` or ``polans-2015``) and, to choose among its eyes,
``subjects`` (numbers as in the data), ``eyes`` (``["right"]``, ``["left"]`` or both) and
``foveal_se_diopters`` (``[low, high]``: the eyes whose foveal spherical equivalent lies within it); the
conditions, every combination of ``pupil_diameter_mm`` (mm, at most the data's), ``field_deg`` ([x, y] pairs as
every vissim field, from the line of sight) and ``correction`` (``"uncorrected"``, ``"sphero-cylinder"``,
``"accommodating"`` with ``accommodation_amplitude_diopters``, or the spectacles worn, a prescription such as
``"-1.00 -0.50 x 90"``), in ``wavelength_nm`` light with the
spectacles ``vertex_distance_mm`` in front of the cornea; and ``mtf_cyc_per_deg``, the frequencies of each eye's MTF.
The defaults are the ``vissim population`` command's. One item per condition.
"""

from __future__ import annotations

import functools

from dataclasses import dataclass

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import (DEFAULT_SPECTACLE_VERTEX_MM, PHOTOPIC_FOCUS_NM, POPULATION_CORRECTION,
                                         POPULATION_FIELD_DEG, POPULATION_MTF_CYC_PER_DEG, POPULATION_PUPILS_MM)
from vissim.checks import ACCOMMODATION_RANGE_DIOPTERS, EYE_MTF_RANGE_CYC_PER_DEG, VERTEX_DISTANCE_RANGE_MM
from vissim.validation.engine.fields import choices, field_error, number, refuse_unknown_keys, text, value_list

__all__ = ["PopulationSettings", "PopulationItem", "read_campaign", "HEAD_KEYS"]

HEAD_KEYS = ("dataset", "subjects", "eyes", "foveal_se_diopters", "pupil_diameter_mm", "field_deg", "correction",
             "accommodation_amplitude_diopters", "wavelength_nm", "vertex_distance_mm", "mtf_cyc_per_deg")


@dataclass(frozen=True)
class PopulationSettings:
    """Which eyes (the dataset and its selection) and the MTF's frequencies, cycles/deg."""

    dataset: str
    subjects: tuple[int, ...] | None
    eyes: tuple[str, ...] | None
    foveal_se_diopters: tuple[float, float] | None
    mtf_cyc_per_deg: tuple[float, ...]

    def selected(self):
        """The `MeasuredWavefront`s this selection names (`select_eyes`), chosen once for all the campaign's
        conditions (a range of foveal spherical equivalents evaluates every eye of the dataset)."""
        return _selected(self)


@functools.lru_cache(maxsize=8)
def _selected(settings: PopulationSettings):
    from vissim.optics.eyes.measured.population import select_eyes

    return select_eyes(settings.dataset, subjects=settings.subjects, eyes=settings.eyes,
                       foveal_se_within_diopters=settings.foveal_se_diopters)


@dataclass(frozen=True)
class PopulationItem:
    """One condition (`PopulationCondition`) every eye is evaluated under; ``name``: its label."""

    name: str
    condition: object

    def as_json(self) -> dict:
        return {"name": self.name, **self.condition.as_json()}

    def key_inputs(self) -> dict:
        return self.condition.as_json()


def _numbers(value, source: str, where: str, unit: str, **bounds) -> tuple[float, ...]:
    items = value if isinstance(value, list) else [value]
    return tuple(number(v, source, f"{where}[{i}]", unit, **bounds) for i, v in enumerate(value_list(items, source,
                                                                                                      where, "[3, 4]")))


def _fields(value, dataset: str, source: str) -> list[tuple[float, float]]:
    from vissim.optics.eyes.measured.datasets import load_dataset

    pairs = value if isinstance(value, list) and value and isinstance(value[0], list) else [value]
    out = []
    for i, pair in enumerate(pairs):
        pair = [pair, 0.0] if isinstance(pair, (int, float)) and not isinstance(pair, bool) else pair
        if not isinstance(pair, list) or len(pair) != 2:
            raise field_error(source, f"campaign.field_deg[{i}]", f"give [x, y] in degrees, got {pair!r}")
        field = tuple(number(v, source, f"campaign.field_deg[{i}]", "deg") for v in pair)
        out.append(_checked(load_dataset(dataset).check_field, source, f"campaign.field_deg[{i}]", field))
    return out


def _checked(check, source: str, where: str, *args, **kwargs):
    """``check(*args, **kwargs)``, its refusal named by the file and ``where``."""
    try:
        return check(*args, **kwargs)
    except VissimInputError as error:
        raise field_error(source, where, str(error)) from None


def _settings(head: dict, source: str) -> PopulationSettings:
    from vissim.optics.eyes.measured.datasets import DATASET_NAMES, load_dataset
    from vissim.optics.eyes.measured.population import select_eyes

    dataset = text(head.get("dataset", ""), source, "campaign.dataset")
    if dataset not in DATASET_NAMES:
        raise field_error(source, "campaign.dataset", f"choose from {', '.join(DATASET_NAMES)}, got {dataset!r}")
    subjects = None
    if "subjects" in head:
        subjects = tuple(value_list(head["subjects"], source, "campaign.subjects", "[1, 17]"))
        if not all(isinstance(s, int) and not isinstance(s, bool) for s in subjects):
            raise field_error(source, "campaign.subjects", f"give subjects' numbers, got {list(subjects)!r}")
    eyes = None if "eyes" not in head else choices(head["eyes"], load_dataset(dataset).eyes, source, "campaign.eyes")
    _checked(select_eyes, source, "campaign.subjects", dataset, subjects=subjects, eyes=eyes)  # each known, once
    se = None
    if "foveal_se_diopters" in head:
        se = _numbers(head["foveal_se_diopters"], source, "campaign.foveal_se_diopters", "D")
        if len(se) != 2 or se[0] > se[1]:
            raise field_error(source, "campaign.foveal_se_diopters", f"give [low, high] in D, got {list(se)!r}")
    frequencies = _numbers(head.get("mtf_cyc_per_deg", list(POPULATION_MTF_CYC_PER_DEG)), source,
                           "campaign.mtf_cyc_per_deg", "cycles/deg", positive=True, hi=EYE_MTF_RANGE_CYC_PER_DEG[1])
    return PopulationSettings(dataset, subjects, eyes, se, frequencies)


def read_campaign(head: dict, source: str) -> tuple[PopulationSettings, tuple[PopulationItem, ...]]:
    """(settings, one item per condition) of a population campaign's ``[campaign]`` ``head`` (module doc)."""
    from vissim.optics.eyes.measured.datasets import load_dataset
    from vissim.optics.eyes.measured.population import parse_correction, population_conditions

    refuse_unknown_keys(head, ("name", "description", "kind", *HEAD_KEYS), source, "campaign")
    settings = _settings(head, source)
    largest = load_dataset(settings.dataset).pupil_mm
    pupils = _numbers(head.get("pupil_diameter_mm", list(POPULATION_PUPILS_MM)), source, "campaign.pupil_diameter_mm", "mm",
                      positive=True, hi=largest)  # at most the data's: nothing is extrapolated
    fields = _fields(head.get("field_deg", list(POPULATION_FIELD_DEG)), settings.dataset, source)
    corrections = [_checked(parse_correction, source, f"campaign.correction[{i}]", text(c, source, "campaign.correction"))
                   for i, c in enumerate(value_list(head.get("correction", [POPULATION_CORRECTION]), source,
                                                    "campaign.correction", f'["{POPULATION_CORRECTION}"]'))]
    amplitude = 0.0 if "accommodation_amplitude_diopters" not in head else number(
        head["accommodation_amplitude_diopters"], source, "campaign.accommodation_amplitude_diopters", "D",
        lo=ACCOMMODATION_RANGE_DIOPTERS[0], hi=ACCOMMODATION_RANGE_DIOPTERS[1], positive=True)
    conditions = _checked(
        population_conditions, source, "campaign", pupils, fields, corrections,
        wavelength_nm=number(head.get("wavelength_nm", PHOTOPIC_FOCUS_NM), source, "campaign.wavelength_nm", "nm",
                             positive=True),
        vertex_mm=number(head.get("vertex_distance_mm", DEFAULT_SPECTACLE_VERTEX_MM), source, "campaign.vertex_distance_mm", "mm",
                         lo=VERTEX_DISTANCE_RANGE_MM[0], hi=VERTEX_DISTANCE_RANGE_MM[1]),
        accommodation_amplitude_diopters=amplitude)
    return settings, tuple(PopulationItem(c.label, c) for c in conditions)
