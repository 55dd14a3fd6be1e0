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

The index does not depend on wavelength (no dispersion): a spectral path carries several
wavelengths along one geometric path, so dispersion would need hero-wavelength handling
that this plugin does not attempt.

Register with `register_plugins` (idempotent) before loading a scene that uses it.
"""

from __future__ import annotations

import logging

from vissim.errors import VissimInputError
from vissim.optics.trial_lens import CROWN_GLASS_INDEX

__all__ = ["REFRACT_BSDF", "register_plugins", "register_once"]

log = logging.getLogger(__name__)

#: Plugin name of the refraction-only dielectric.
REFRACT_BSDF = "vissim_refract"
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
            reflection = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            transmission = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            self.m_components = [reflection, transmission]
            self.m_flags = reflection | transmission

        def sample(self, ctx, si, sample1, sample2, active=True):
            cos_theta_i = mi.Frame3f.cos_theta(si.wi)
            r_i, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, mi.Float(self.eta))
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
            return bs, dr.select(active, mi.Spectrum(weight), mi.Spectrum(0.0))

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
                    f"fresnel_loss={self.fresnel_loss}]")

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
