"""Mitsuba plugins of the optical bench: a deterministic, refraction-only dielectric BSDF.

Mitsuba's stock ``dielectric`` chooses reflection or refraction at random with the Fresnel
probabilities.  On a lens bench that throws away ~8 % of the paths at two uncoated surfaces
(each becoming a ghost reflection that mostly leaves the scene) and adds noise; its exterior
index also defaults to air (1.000277), not 1.

``vissim_refract`` instead:

* always refracts (Snell's law with the *shading* normal, i.e. the mesh's exact interpolated
  vertex normals); only under total internal reflection does it reflect, with weight 1;
* is deterministic: it consumes no random numbers, so the only noise in a bench render is
  the pixel and aperture sampling of the camera;
* weights the refracted path by 1 (``fresnel_loss = False``, the default: an ideally coated
  lens) or by the unpolarised Fresnel transmittance 1 - R (``fresnel_loss = True``: uncoated
  glass; the reflected part is dropped, not traced);
* scales radiance by (eta_t/eta_i)^-2 across the surface in radiance transport, as Mitsuba's
  dielectric does, so a path entering and leaving glass carries the radiance it started with;
* has exterior index exactly 1.0; ``int_ior`` is the glass index.

Dispersion (``dispersion = "crown"``; default ``"none"``): the glass becomes
`vissim.optics.rx.glass.glass_like_crown` of ``int_ior`` -- a Cauchy glass with index ``int_ior`` at
the d line and spectacle crown's Abbe number, the glass the bench's exact trace uses (with
``int_ior`` 1.523 it is `vissim.optics.rx.glass.SPECTACLE_CROWN`).  Then:

* **spectral variants**: a path carries several wavelengths (Mitsuba: 4, the hero
  ``si.wavelengths[0]`` and three rotations of it, each distributed like the hero).  The surface
  refracts at the hero's index, and the other wavelengths end there: their weight is 0 and the
  hero's is multiplied by the number of wavelengths, as pbrt-v4's
  ``SampledWavelengths::TerminateSecondary`` (src/pbrt/util/spectrum.h: the secondary pdfs
  set to 0, the hero's divided by the count) -- unbiased because the hero alone is a sample
  of the wavelength distribution.  Only the *first* dispersive interface of a path multiplies;
  later ones find the secondaries gone.  Mitsuba's BSDFs keep no path state, so "first" is
  found geometrically: the ray back along ``wi`` meets nothing (the path came straight from
  the sensor, which is not geometry).  This holds where a camera path reaches its first lens
  surface from the sensor directly, as on the benches; a scene with another surface in front
  of the lenses would need another rule (``sensor_terminates_secondary = True`` never
  multiplies: for a sensor that ends the secondaries itself).  Needs `attach_scene` after
  loading (`vissim.render.run.render_scene` does it).
* **what it costs**: the luminance of a path then rests on one wavelength, not four.  Per-pixel
  variance, hero-only over four wavelengths through the same +2 D lens, equal spp
  (benchmarks/bench_dispersion.py, 64 x 64 px, 16 spp, 8 seeds): Sloan K at LogMAR 1.0,
  5.1x with the bench's multijitter sampler (4.8x independent); a uniform white, 73x
  (multijitter; 900x independent) -- there the four wavelengths alone are nearly noiseless,
  and one wavelength's ``ȳ(λ)/p(λ)`` is what is left (2.8 % RMS per pixel at 16 spp).  Equal
  noise needs about 5x the spp on a letter chart.
* **mono and RGB variants**: one index, at ``wavelength_nm`` (default the d line, where the
  glass has ``int_ior`` bit for bit, so the default render is unchanged).

Without ``dispersion`` the index is ``int_ior`` at every wavelength (``wavelength_nm`` unused).

Register with `register_plugins` (idempotent) before loading a scene that uses it.
"""

from __future__ import annotations

import logging

from vissim.errors import VissimInputError
from vissim.optics.rx.glass import D_LINE_NM, glass_like_crown
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX

__all__ = ["REFRACT_BSDF", "DISPERSIONS", "register_plugins", "register_once", "attach_scene"]

log = logging.getLogger(__name__)

#: Plugin name of the refraction-only dielectric.
REFRACT_BSDF = "vissim_refract"
#: Values of the ``dispersion`` property: no dispersion, or crown's Abbe number at ``int_ior``.
DISPERSIONS = ("none", "crown")
_registered: set[tuple[str, str]] = set()


def _make_class(mi, dr):
    class RefractOnlyDielectric(mi.BSDF):
        """See the module docstring."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.int_ior = float(props.get("int_ior", CROWN_GLASS_INDEX))
            ext_ior = float(props.get("ext_ior", 1.0))
            if self.int_ior <= 0.0 or ext_ior <= 0.0:
                raise VissimInputError(f"indices of refraction must be > 0, got {self.int_ior:g} and {ext_ior:g}")
            self.ext_ior = ext_ior
            self.fresnel_loss = bool(props.get("fresnel_loss", False))
            self.eta = self.int_ior / self.ext_ior
            self._read_dispersion(props)
            reflection = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            transmission = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            self.m_components = [reflection, transmission]
            self.m_flags = reflection | transmission

        def _read_dispersion(self, props):
            self.dispersion = str(props.get("dispersion", "none"))
            if self.dispersion not in DISPERSIONS:
                raise VissimInputError(f"dispersion must be one of {', '.join(DISPERSIONS)}, got {self.dispersion!r}")
            self.wavelength_nm = float(props.get("wavelength_nm", D_LINE_NM))
            self.sensor_terminates = bool(props.get("sensor_terminates_secondary", False))
            self.scene = None
            self.glass = None
            if self.dispersion == "crown":
                self.glass = glass_like_crown(self.int_ior)
                if not mi.is_spectral:
                    self.eta = self.glass.index(self.wavelength_nm) / self.ext_ior
                elif mi.is_polarized:
                    raise VissimInputError("dispersion needs an unpolarised variant; got " + mi.variant())

        def _hero_eta(self, si):
            """Relative index at the hero wavelength (`vissim.optics.rx.glass.CauchyGlass.index_unchecked`)."""
            return self.glass.index_unchecked(si.wavelengths[0]) / self.ext_ior

        def _hero_only(self, si, weight, active):
            """The spectrum of ``weight`` on the hero wavelength alone, times the count at the first interface."""
            lanes = dr.size_v(mi.Spectrum)
            gain = mi.Float(1.0)
            if not self.sensor_terminates:
                if self.scene is None:
                    raise VissimInputError("vissim_refract with dispersion in a spectral variant needs "
                                           "vissim.render.plugins.attach_scene(scene) after loading")
                came_from_surface = self.scene.ray_test(si.spawn_ray(si.to_world(si.wi)), active)
                gain = dr.select(came_from_surface, mi.Float(1.0), mi.Float(lanes))
            return mi.Spectrum(weight * gain, *([0.0] * (lanes - 1)))

        def sample(self, ctx, si, sample1, sample2, active=True):
            hero = mi.is_spectral and self.glass is not None
            cos_theta_i = mi.Frame3f.cos_theta(si.wi)
            eta = self._hero_eta(si) if hero else mi.Float(self.eta)
            r_i, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, eta)
            total_internal = r_i >= 1.0
            bs = dr.zeros(mi.BSDFSample3f)
            bs.pdf = mi.Float(1.0)
            bs.sampled_component = dr.select(total_internal, mi.UInt32(0), mi.UInt32(1))
            bs.sampled_type = dr.select(
                total_internal, mi.UInt32(+mi.BSDFFlags.DeltaReflection), mi.UInt32(+mi.BSDFFlags.DeltaTransmission)
            )
            bs.wo = dr.select(total_internal, mi.reflect(si.wi), mi.refract(si.wi, cos_theta_t, eta_ti))
            bs.eta = dr.select(total_internal, mi.Float(1.0), eta_it)
            weight = mi.Float(1.0)
            if self.fresnel_loss:
                weight = dr.maximum(1.0 - r_i, 0.0)
            if ctx.mode == mi.TransportMode.Radiance:
                weight = weight * dr.square(eta_ti)
            weight = dr.select(total_internal, mi.Float(1.0), weight)
            spectrum = self._hero_only(si, weight, active) if hero else mi.Spectrum(weight)
            return bs, dr.select(active, spectrum, mi.Spectrum(0.0))

        def eval(self, ctx, si, wo, active=True):
            return mi.Spectrum(0.0)

        def pdf(self, ctx, si, wo, active=True):
            return mi.Float(0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return mi.Spectrum(0.0), mi.Float(0.0)

        def traverse(self, callback):
            pass

        def to_string(self):
            return (f"RefractOnlyDielectric[int_ior={self.int_ior}, ext_ior={self.ext_ior}, "
                    f"fresnel_loss={self.fresnel_loss}, dispersion={self.dispersion}]")

    return RefractOnlyDielectric


def register_once(mi, name: str, kind: str, make_class) -> None:
    """Register plugin ``name`` (``kind`` "bsdf" or "sensor") with the current variant, once.

    ``make_class(mi, dr)`` builds the Python class for the variant; Mitsuba needs one
    registration per variant.
    """
    key = (mi.variant(), name)
    if key in _registered:
        return
    import drjit as dr

    cls = make_class(mi, dr)
    register = mi.register_bsdf if kind == "bsdf" else mi.register_sensor
    register(name, lambda props: cls(props))
    _registered.add(key)
    log.debug("registered %s for %s", name, key[0])


def register_plugins(mi) -> None:
    """Register `REFRACT_BSDF` with the current Mitsuba variant (once per variant)."""
    register_once(mi, REFRACT_BSDF, "bsdf", _make_class)


def attach_scene(mi, scene, *, detach: bool = False) -> None:
    """Give each dispersive `REFRACT_BSDF` of the loaded ``scene`` the scene (its first-interface test).

    ``detach``: take it back after rendering (the BSDF and the scene would otherwise hold each other).
    """
    for shape in scene.shapes():
        bsdf = shape.bsdf()
        if getattr(bsdf, "glass", None) is not None and hasattr(bsdf, "sensor_terminates"):
            bsdf.scene = None if detach else scene
