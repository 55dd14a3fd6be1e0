"""One vocabulary: each concept's one spelling per surface (docs/conventions.md, "Defaults and words").

`CONCEPTS` names, for every concept a user meets in more than one place, its command-line flag, its
campaign-file key, its scene-file key and its Python (public API) parameter name; `tests/test_vocabulary.py`
walks every command's options, every campaign and scene loader's keys and the public signatures, and
refuses a concept spelled a second way.  `RENAMED_KEYS` lists the file keys that were renamed: a file
that still spells one the old way is refused with one line naming the new key (`renamed_key_error`),
never read under both names.
"""

from __future__ import annotations

from dataclasses import dataclass

from vissim.errors import VissimInputError

__all__ = ["Concept", "CONCEPTS", "RENAMED_KEYS", "RENAMED_KEYS_ELSEWHERE", "renamed_key_error", "refuse_renamed_keys"]


@dataclass(frozen=True)
class Concept:
    """One concept's spellings (None where a surface has no such thing) and the words that mean it.

    ``words`` are the stems (lower case, ``_`` between words) by which any spelling of the concept is
    recognised, e.g. ``("pupil",)`` recognises ``pupil_mm``, ``pupil_diameter_mm`` and ``--pupil-mm``;
    ``excluding`` are stems that, present in a name, make it another concept (``zernike_pupil``)."""

    name: str
    flag: str | None
    campaign_key: str | None
    scene_key: str | None
    api: str | None
    unit: str
    default: str
    limit: str
    words: tuple[str, ...]
    excluding: tuple[str, ...] = ()


CONCEPTS: tuple[Concept, ...] = (
    Concept("entrance pupil diameter", "--pupil-mm", "pupil_diameter_mm", "pupil_diameter_mm", "pupil_diameter_mm",
            "mm", "4 (an eye's; a camera's: focal length / f-number)",
            "an eye's 1-10 (EYE_PUPIL_RANGE_MM), any entrance pupil 0.01-1000 (ENTRANCE_PUPIL_RANGE_MM)",
            ("pupil", "pupil_diameter"), ("zernike_pupil", "thesis_pupil", "fit_pupil", "pupil_distance", "pupils")),
    Concept("iris (stop) diameter", "--iris-mm", None, "iris_mm", "iris_mm", "mm", "none (the pupil is given)",
            "as the pupil", ("iris", "iris_diameter")),
    Concept("vertex distance (trial or spectacle lens to the viewer)", "--vertex-mm", "vertex_distance_mm",
            "vertex_distance_mm", "vertex_distance_mm", "mm",
            "camera 10 (THESIS_VERTEX_DISTANCE_MM), eye behind a trial lens 15 (EYE_VERTEX_DISTANCE_MM), "
            "spectacles before a schematic eye 12 (DEFAULT_SPECTACLE_VERTEX_MM)",
            "0-200 (VERTEX_DISTANCE_RANGE_MM)", ("vertex", "vertex_distance", "lens_distance", "trial_lens_distance")),
    Concept("wavelength", "--wavelength-nm", "wavelength_nm", "wavelength_nm", "wavelength_nm", "nm",
            "550 (DEFAULT_WAVELENGTH_NM); the bench's glass at its d line 587.56, a schematic eye at its model's "
            "reference, the population at 555 (V(λ)'s peak): each said in its help",
            "200-2000 (WAVELENGTH_RANGE_NM); an eye's 365-1014, its light 365-850",
            ("wavelength", "lambda", "wl"), ("wavelengths", "reference_wavelength", "lca_reference", "channel")),
    Concept("accommodation exerted", "--accommodation-diopters", "accommodation_diopters", "accommodation_diopters",
            "accommodation_diopters", "D", "0 (relaxed)", "0-20 (ACCOMMODATION_RANGE_DIOPTERS), the model's own",
            ("accommodation", "accommodated"), ("accommodation_amplitude", "amplitude")),
    Concept("amplitude of accommodation", "--accommodation-amplitude-diopters", "accommodation_amplitude_diopters",
            None, "accommodation_amplitude_diopters", "D", "atv simulate 8; population: none (required with "
            "accommodating)", "0-20 (ACCOMMODATION_RANGE_DIOPTERS)", ("amplitude", "accommodation_amplitude")),
    Concept("field angle", "--field-deg", "field_deg", "field_deg", "field_deg", "degrees ([x, y])", "0,0",
            "the model's or the data's field", ("field",),
            ("field_step", "field_map", "field_axis", "energy_in_field", "field_arcmin", "fields_deg", "frame_field",
             "field_from", "in_field", "field_nodes")),
    Concept("spectrum (a named light)", "--spectrum", "spectrum", "spectrum", "spectrum", "(a name)",
            "none: one wavelength", "photopic, equal-energy (the command's choices)", ("spectrum", "light"),
            ("light_range",)),
    Concept("the eye's prescription (its correcting lens)", "--rx", "prescription", "prescription", "rx",
            "D (sphere, cylinder) and degrees (axis)", "none (emmetropic)", "each principal meridian ±30 D "
            "(TRIAL_LENS_RANGE_DIOPTERS)", ("rx", "prescription", "eye_prescription"),
            ("camera_prescription", "fit_rx", "prescription_from", "refractive_error")),
    Concept("image size", "--size", "size_px", "size_px", "size_px", "px (N, or ROWSxCOLS in array order)",
            "each command's, said in its help", "the image's memory (check_allocation)", ("size", "shape"),
            ("size_text", "tile", "step_size", "font_size")),
    Concept("chart distance (the chart to the viewer)", "--chart-distance-m", "chart_distance_m", "chart_distance_m",
            "chart_distance_mm", "m (mm in DslrBench, whose lengths are all mm)",
            "the thesis's bench 0.9144 (THESIS_CHART_DISTANCE_MM); an eye's 6 (DEFAULT_CHART_DISTANCE_M)",
            "an eye's VIEWING_DISTANCE_RANGE_M, the bench's OBJECT_DISTANCE_RANGE_M",
            ("chart_distance", "viewing_distance")),
    Concept("angular sampling", "--arcmin-per-px", "arcmin_per_px", "arcmin_per_px", "arcmin_per_px", "arcmin/px",
            "each command's, said in its help", "ARCMIN_PER_PX_RANGE", ("arcmin_per_px", "sampling_arcmin")),
)

#: Campaign- and scene-file keys renamed (old -> new): the old one is refused, naming the new.
RENAMED_KEYS: dict[str, str] = {
    "vertex_mm": "vertex_distance_mm",
    "pupil_mm": "pupil_diameter_mm",
    "accommodation": "accommodation_diopters",
    "field": "field_deg",
    "light": "wavelength_nm (a number) or spectrum = \"photopic\"",
    "rx": "prescription",
    "eye": "prescription",
    "letters": "letter (a list sweeps it)",
    "logmars": "logmar (a list sweeps it)",
    "polarities": "polarity (a list sweeps it)",
    "spheres": "lens (a number is a sphere lens; a list sweeps it)",
    "cylinders": "lens (a list sweeps it)",
    "sphere": "sphere_diopters",
    "cylinder": "cylinder_diopters",
    "axis": "axis_deg",
    "distance_mm": "vertex_distance_mm",
    "distance_m": "chart_distance_m",
}

#: Keys renamed one way in one table and another way in another (old -> new): refused as `RENAMED_KEYS` are,
#: where the table takes the new key (a DSLR scene's ``[holder] distance_mm`` is ``vertex_distance_mm``, its
#: ``[chart] distance_mm`` ``chart_distance_m``).
RENAMED_KEYS_ELSEWHERE: dict[str, str] = {
    "distance_mm": "chart_distance_m (metres, not mm)",
}


def renamed_key_error(where: str, key: str, new: str | None = None) -> VissimInputError:
    """The one-line refusal of a renamed key: ``WHERE: 'vertex_mm' is now 'vertex_distance_mm'`` (``new``: the
    new key and its note, default `RENAMED_KEYS`'s)."""
    new = RENAMED_KEYS[key] if new is None else new
    quoted = f"'{new}'" if " " not in new else f"'{new.split(' ', 1)[0]}' {new.split(' ', 1)[1]}"
    return VissimInputError(f"{where}: {key!r} is now {quoted}")


def refuse_renamed_keys(keys, allowed, where: str) -> None:
    """Refuse the first of ``keys`` (a table's keys) that `RENAMED_KEYS` renamed to a key ``allowed`` holds."""
    for key in sorted(keys):
        if key in allowed:
            continue
        for renamed in (RENAMED_KEYS, RENAMED_KEYS_ELSEWHERE):
            if key in renamed and renamed[key].split(" ", 1)[0] in allowed:
                raise renamed_key_error(where, key, renamed[key])
