"""The two depth scenes of ``scenes/depth_panels.toml`` and ``scenes/depth_tilted.toml``, built in code.

Tests build small variants from them (other distances, sizes, letters), and
``test_depth_scene.py`` pins the scene files against them.
"""

from vissim.bench.depth.scene import ChartPanel, DepthScene, PanelChart, TiltedChart
from vissim.errors import VissimInputError

#: The panels' distances: near work, the thesis's 3 ft, across the room, far.
DEFAULT_DISTANCES_M = (0.4, 0.9144, 2.0, 6.0)


def default_panels_scene(distances_m=DEFAULT_DISTANCES_M, *, logmar: float = 0.5, letters: str | None = None,
                         padding_arcmin: float = 8.0, step_arcmin=(40.0, 20.0), size_px=(128, 192)) -> DepthScene:
    """Charts at ``distances_m``, far to near from upper right to lower left, each overlapping the next.

    Each panel shows one Sloan letter (``letters``: one per panel, default H V Z D S ...) at
    ``logmar``; neighbouring centres are ``step_arcmin`` (right, up) apart.
    """
    placed = sorted(distances_m, reverse=True)
    letters = letters or "HVZDSNCKOR"[: len(placed)]
    if len(letters) != len(placed):
        raise VissimInputError(f"give one letter per panel: {len(placed)} distances, letters {letters!r}")
    panels = []
    for i, (distance, letter) in enumerate(zip(placed, letters)):
        step = 0.5 * (len(placed) - 1) - i
        center = (step * step_arcmin[0], step * step_arcmin[1])
        panels.append(ChartPanel(distance, center, PanelChart(letter, logmar, padding_arcmin=padding_arcmin)))
    return DepthScene(tuple(panels), size_px=tuple(size_px))


def default_tilted_scene(distance_left_m: float = 0.5, distance_right_m: float = 3.0, *,
                         size_px=(96, 192)) -> DepthScene:
    """A tilted chart spanning ``distance_left_m`` to ``distance_right_m`` across the image."""
    chart = PanelChart("HVZDS NCKOR", 0.5, padding_arcmin=8.0)
    return DepthScene((TiltedChart(distance_left_m, distance_right_m, (0.0, 0.0), chart),), size_px=tuple(size_px))
