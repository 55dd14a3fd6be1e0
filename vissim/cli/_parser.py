"""The argument parser every sub-command uses: one ``vissim: error:`` line for any bad argument.

* argparse's own errors (unknown option, missing argument, bad choice) are printed as one line,
  ``vissim: error: <message>``, and exit 2 (no usage block).
* ``type=float`` / ``type=int`` options refuse NaN and infinity and name the option's unit;
  counts (``--spp``, ``--size``, ...), pupils, samplings and wavelengths must be positive, and
  seeds 32-bit.  `Number` adds a
  range (``Number(float, positive=True)``) or allows infinity.
* The unit is the option's own name where it ends in one (``--pupil-mm``, ``--arcmin-per-px``,
  ``--accommodation-diopters``), else its metavar (``D``, ``DEG``, ``MM``), else `UNITS_BY_DEST`.
"""

from __future__ import annotations

import argparse
import math
import sys
import dataclasses
from dataclasses import dataclass

from vissim import checks
from vissim.checks import MAX_POWER_DIOPTERS, MAX_SAMPLER_SEED, MAX_SPP, range_text

__all__ = ["Number", "VissimArgumentParser", "unit_of"]

#: Name endings that are units (units go in names).
_UNIT_SUFFIXES = (
    ("_arcmin_per_px", "arcmin per pixel"), ("_per_px", "per pixel"), ("_mm", "mm"), ("_nm", "nm"),
    ("_deg", "degrees"), ("_diopters", "dioptres"), ("_arcmin", "arcmin"), ("_m", "m"),
)
_UNITS_BY_METAVAR = {"D": "dioptres", "DEG": "degrees", "MM": "mm", "NM": "nm", "M": "m"}
#: Options whose name carries no unit.
UNITS_BY_DEST = {
    "spp": "samples per pixel", "aux_spp": "samples per pixel", "size": "pixels", "rays": "rays",
    "workers": "worker processes", "max_layers": "depth layers", "seed": "(a whole number)", "age": "years",
    "dpi": "dots per inch", "f_number": "(f-number)", "logmar": "LogMAR", "logmar_step": "LogMAR",
    "index": "(refractive index)", "gamma": "(display gamma)", "level": "(confidence level)",
    "guess": "(a probability)", "lapse": "(a probability)",
}


def unit_of(action: argparse.Action) -> str:
    """The unit an option's value is in, for error messages."""
    if isinstance(action.type, Number) and action.type.unit:
        return action.type.unit
    dest = action.dest
    if dest in UNITS_BY_DEST:
        return UNITS_BY_DEST[dest]
    for suffix, unit in _UNIT_SUFFIXES:
        if ("_" + dest).endswith(suffix):
            return unit
    if isinstance(action.metavar, str) and action.metavar in _UNITS_BY_METAVAR:
        return _UNITS_BY_METAVAR[action.metavar]
    return "(a number)"


@dataclass(frozen=True)
class Number:
    """A numeric argument type: ``kind`` (float or int), an optional range, infinity refused unless allowed."""

    kind: type = float
    positive: bool = False
    nonnegative: bool = False
    maximum: float | None = None
    max_magnitude: float | None = None
    allow_inf: bool = False
    unit: str | None = None
    bounds: tuple[float, float] | None = None
    below_upper: bool = False

    def parse(self, text: str, name: str, unit: str) -> float | int:
        stripped = text.strip()
        try:
            value = float(stripped)
        except ValueError:
            kind = "a whole number" if self.kind is int else "a number"
            raise argparse.ArgumentTypeError(f"{name} must be {kind} in {unit}, got {stripped!r}") from None
        if math.isnan(value) or (math.isinf(value) and not self.allow_inf):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number in {unit}, got {stripped!r}")
        if self.bounds is not None and math.isfinite(value) and not (self.bounds[0] <= value <= self.bounds[1] and (
                value < self.bounds[1] or not self.below_upper)):
            lower = "more than" if self.positive else "at least"
            allowed = (f"{lower} {self.bounds[0]:g} and less than {self.bounds[1]:g} {unit}" if self.below_upper
                       else range_text(self.bounds, unit))
            raise argparse.ArgumentTypeError(f"{name} must be {allowed}, got {stripped!r}")
        if self.kind is int:
            if abs(value) > checks.MAX_WHOLE_NUMBER:  # no count or index is this large, and floats skip whole numbers there
                raise argparse.ArgumentTypeError(f"{name} must be a whole number in {unit} below 2^53, got {stripped!r}")
            if value != int(value):
                raise argparse.ArgumentTypeError(f"{name} must be a whole number in {unit}, got {stripped!r}")
            value = int(value)
        if self.positive and not value > 0:
            raise argparse.ArgumentTypeError(f"{name} must be > 0 {unit}, got {stripped!r}")
        if self.nonnegative and not value >= 0:
            raise argparse.ArgumentTypeError(f"{name} must be >= 0 {unit}, got {stripped!r}")
        if self.max_magnitude is not None and abs(value) > self.max_magnitude:
            raise argparse.ArgumentTypeError(f"{name} must lie within +-{self.max_magnitude:g} {unit}, got {stripped!r}")
        if self.maximum is not None and value > self.maximum:
            raise argparse.ArgumentTypeError(f"{name} must be at most {self.maximum:g} {unit}, got {stripped!r}")
        return value

    def __call__(self, text: str):  # argparse checks that a type is callable; parsing goes through parse
        return self.parse(text, "value", self.unit or "(a number)")


#: The range of plain ``type=int`` options by name: counts are positive, seeds 32-bit.
_INTS_BY_DEST = {
    "seed": Number(int, nonnegative=True, maximum=MAX_SAMPLER_SEED),
    **{dest: Number(int, positive=True, maximum=MAX_SPP) for dest in ("spp", "aux_spp")},
    **{dest: Number(int, positive=True) for dest in ("size", "rays")},
    "workers": Number(int, positive=True, maximum=checks.MAX_WORKERS),
}
#: Powers, dioptres: within +-MAX_POWER_DIOPTERS.
_POWERS = {"sphere", "cylinder", "back_surface_diopters",
           "accommodation_diopters", "accommodation_amplitude_diopters", "proximal_diopters"}
#: Plain ``type=float`` options that only make sense positive.
_POSITIVE_FLOATS = {
    "pupil_mm", "zernike_pupil_mm", "arcmin_per_px", "wavelength_nm", "lca_reference_nm", "channel_fwhm_nm",
    "dpi", "f_number", "focal_length_mm", "chart_distance_m", "summation_arcmin", "layer_spacing_fraction", "index",
}


#: Plain number options whose quantity has one range every command keeps (`vissim.checks`, docs/conventions.md,
#: "Input ranges and refusals"); a command may narrow it further (an eye's wavelengths, its model's accommodation).
RANGES_BY_DEST = {
    "arcmin_per_px": checks.ARCMIN_PER_PX_RANGE,
    "wavelength_nm": checks.WAVELENGTH_RANGE_NM,
    "lca_reference_nm": checks.WAVELENGTH_RANGE_NM,
    "f_number": checks.F_NUMBER_RANGE,
    "focal_length_mm": checks.FOCAL_LENGTH_RANGE_MM,
    "focus_distance_m": checks.OBJECT_DISTANCE_RANGE_M,
    "axis": checks.AXIS_RANGE_DEG,
    "vertex_mm": checks.VERTEX_DISTANCE_RANGE_MM,
    "index": checks.REFRACTIVE_INDEX_RANGE,
    "layer_spacing_fraction": checks.LAYER_SPACING_FRACTION_RANGE,
    "accommodation_diopters": checks.ACCOMMODATION_RANGE_DIOPTERS,
    "accommodation_amplitude_diopters": checks.ACCOMMODATION_RANGE_DIOPTERS,
    "proximal_diopters": checks.ACCOMMODATION_RANGE_DIOPTERS,
    "display_code": checks.DISPLAY_CODE_RANGE,
    "full_capture_code": checks.DISPLAY_CODE_RANGE,
    "logmar": checks.LOGMAR_RANGE,
    "logmar_step": checks.LOGMAR_STEP_RANGE,
    "dpi": checks.PRINT_DPI_RANGE,
    "margin_px": checks.MARGIN_RANGE_PX,
    "pixel_intensity": (0.0, checks.MAX_PIXEL_RADIANCE),
    "white_radiance": (0.0, checks.MAX_PIXEL_RADIANCE),
    "field_step_deg": (0.0, 2 * checks.MAX_FIELD_DEG),
    "window_diopters": checks.ATV_PARABOLA_WINDOW_RANGE_DIOPTERS,
    "summation_arcmin": checks.SUMMATION_RANGE_ARCMIN,
    "thickness_mm": checks.BENCH_LENGTH_RANGE_MM,
    "level": (0.0, 1.0),
    "guess": checks.GUESS_LAPSE_RANGE,
    "lapse": checks.GUESS_LAPSE_RANGE,
}
#: Of those, the quantities that must exceed their lower bound (an f-number or a print resolution of 0 is none).
_ABOVE_LOWER = {"white_radiance", "field_step_deg", "logmar_step", "summation_arcmin", "level"}
#: Of those, the quantities that must stay below their upper bound (a confidence level of 1 is no interval).
_BELOW_UPPER = {"level", "guess", "lapse"}


def _number_type(action: argparse.Action) -> Number | None:
    if isinstance(action.type, Number):
        return action.type
    bounds = RANGES_BY_DEST.get(action.dest)
    if action.type is int:
        number = _INTS_BY_DEST.get(action.dest, Number(int))
        return number if bounds is None else dataclasses.replace(number, bounds=bounds)
    if action.type is float:
        if action.dest in _POWERS:
            return Number(float, max_magnitude=MAX_POWER_DIOPTERS, bounds=bounds)
        return Number(float, positive=action.dest in _POSITIVE_FLOATS or action.dest in _ABOVE_LOWER, bounds=bounds,
                      below_upper=action.dest in _BELOW_UPPER)
    return None


class VissimArgumentParser(argparse.ArgumentParser):
    """`argparse.ArgumentParser` with one-line errors and checked numbers (module doc)."""

    def _get_value(self, action, arg_string):
        number = _number_type(action)
        if number is None:
            return super()._get_value(action, arg_string)
        name = "/".join(action.option_strings) or action.dest
        try:
            return number.parse(arg_string, name, unit_of(action))
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentError(None, str(exc)) from None

    def parse_args(self, args=None, namespace=None):
        self._help_prog = self._command_prog(list(sys.argv[1:] if args is None else args))
        return super().parse_args(args, namespace)

    def _command_prog(self, argv: list[str]) -> str:
        """``vissim atv simulate`` for argv naming that command: the help an error points to."""
        parser = self
        for token in argv:
            commands = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})
            if token in commands:
                parser = commands[token]
            elif not token.startswith("-"):
                break
        return parser.prog

    def error(self, message: str):
        message = " ".join(message.split()) + _eye_hint(message)
        sys.stderr.write(f"vissim: error: {message} (see '{getattr(self, '_help_prog', self.prog)} --help')\n")
        sys.exit(2)


def _eye_hint(message: str) -> str:
    """A hint when a stray argument names an eye: every command chooses its eye with ``--eye-model``."""
    if not message.startswith("unrecognized arguments:"):
        return ""
    from vissim.optics.eyes.measured.measured_eye import is_measured_name
    from vissim.optics.eyes.models import EYE_MODELS

    names = [t for t in message.split(":", 1)[1].split() if t in EYE_MODELS or is_measured_name(t)]
    return f"; an eye is chosen with --eye-model {names[0]}" if names else ""
