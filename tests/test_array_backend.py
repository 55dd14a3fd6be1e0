"""The array backend (NumPy on the CPU, CuPy on a CUDA GPU) and the blurs that run on it.

The CPU backend runs the GPU path's code with NumPy, so these tests pin that code on every
machine: ``blur_image_on`` against ``blur_image`` (overlap-save squares or one FFT: the same
convolution) and ``blur_depth(device="cpu")`` against itself, to float32 round-off (abs 1e-5 on
[0, 1] images, i.e. > 100 dB).  On a machine with CuPy and a CUDA device the GPU must match
the CPU within 60 dB PSNR (issue 15); without one those tests are skipped.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.fft

from vissim.errors import VissimInputError
from vissim.optics.depth import depth_map as depth_module
from vissim.optics.runtime.array_backend import ArrayBackend, array_backend, array_module, cuda_available
from vissim.optics.blur.convolve import blur_image
from vissim.optics.blur.device import blur_image_on
from vissim.optics.depth.depth_map import blur_depth
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront

needs_gpu = pytest.mark.skipif(not cuda_available(), reason="no CuPy with a CUDA device")


def psf(sphere=-1.0, step=1.0):
    front = Wavefront.from_prescription(Prescription(sphere), 3.0)
    return compute_psf(front, arcmin_per_px=step, size_px=suggested_size_px(front, step))


def image(shape, seed=0):
    return np.random.default_rng(seed).random(shape).astype(np.float32)


def depth_scene():
    depth = np.full((64, 96), 3.0)
    depth[16:48, 20:60] = 0.5
    depth[40:, :] = np.linspace(0.4, 2.0, 24)[:, None]
    return image((64, 96, 3), 3), depth


def psnr_db(a, b):
    return 10 * math.log10(1.0 / float(np.mean((np.asarray(a, np.float64) - b) ** 2)))


def test_cpu_backend_is_numpy_and_refuses_unknown_devices():
    backend = array_backend("cpu")
    assert backend.xp is np and array_module(np.zeros(2)) is np
    assert backend.to_numpy(backend.asarray([1.0, 2.0])).tolist() == [1.0, 2.0]
    with pytest.raises(VissimInputError, match="device must be one of cpu, cuda, auto"):
        array_backend("tpu")


@pytest.mark.skipif(cuda_available(), reason="a CUDA device is present")
def test_asking_for_cuda_without_a_gpu_says_why_and_auto_falls_back_to_the_cpu():
    with pytest.raises(VissimInputError, match="device 'cuda' asked for, but CuPy"):
        array_backend("cuda")
    assert array_backend("auto").name == "cpu"


@pytest.mark.parametrize("padding", ["constant", "edge", "reflect", "wrap"])
def test_blur_image_on_the_cpu_backend_equals_blur_image(padding):
    picture = image((300, 700, 3))  # wide enough for blur_image's overlap-save squares
    kernel = psf()
    expected = blur_image(picture, kernel, arcmin_per_px=1.0, padding=padding)
    np.testing.assert_allclose(blur_image_on(picture, kernel, arcmin_per_px=1.0, padding=padding), expected, atol=1e-5)


def test_blur_image_on_takes_one_psf_per_channel_and_a_background():
    picture = image((40, 50, 3), 1)
    kernels = [psf(-1.0), psf(-2.0), psf(-1.0)]
    expected = blur_image(picture, kernels, arcmin_per_px=1.0, background=[0.1, 0.2, 0.3])
    got = blur_image_on(picture, kernels, arcmin_per_px=1.0, background=[0.1, 0.2, 0.3])
    np.testing.assert_allclose(got, expected, atol=1e-5)
    with pytest.raises(VissimInputError, match="arcmin/px"):
        blur_image_on(picture, psf(step=0.5), arcmin_per_px=1.0)


@needs_gpu
def test_gpu_blur_image_matches_the_cpu_within_60_db():
    picture, kernel = image((1080, 1920, 3)), psf(-1.5)
    cpu = blur_image(picture, kernel, arcmin_per_px=1.0)
    assert psnr_db(blur_image_on(picture, kernel, arcmin_per_px=1.0, device="cuda"), cpu) >= 60.0


@needs_gpu
def test_gpu_blur_depth_matches_the_cpu_within_60_db():
    picture, depth = depth_scene()
    kwargs = dict(rx=Prescription(-1.5), pupil_diameter_mm=4.0, arcmin_per_px=1.0)
    cpu = blur_depth(picture, depth, **kwargs).image
    assert psnr_db(blur_depth(picture, depth, device="cuda", **kwargs).image, cpu) >= 60.0


def test_blur_depth_by_the_device_code_equals_the_cpus(monkeypatch):
    # A NumPy backend that is not the CPU's takes the GPU's route (kernel spectra cached "on the
    # device", transforms without scipy's workers): the same numbers as the CPU, to float32 round-off.
    picture, depth = depth_scene()
    kwargs = dict(rx=Prescription(-1.5), pupil_diameter_mm=4.0, arcmin_per_px=1.0, padding="reflect")
    cpu = blur_depth(picture, depth, **kwargs).image
    spectra_sent = []

    class NumpyAsDevice(ArrayBackend):
        def asarray(self, array, dtype=None):
            spectra_sent.append(np.iscomplexobj(array))
            return np.asarray(array, dtype=dtype)

    monkeypatch.setattr(depth_module, "array_backend", lambda name: NumpyAsDevice("numpy-as-device", np, scipy.fft))
    np.testing.assert_allclose(blur_depth(picture, depth, **kwargs).image, cpu, atol=1e-5)
    assert any(spectra_sent)  # kernel spectra went to the "device"


def test_a_device_convolves_each_psf_as_the_cpu_does():
    # Transient PSFs (as blur_depth's reflected layers are) die after use, and CPython may give the
    # next one the same id: each must still be convolved with its own spectrum.  Oracle: the CPU's
    # convolution of the same planes with each PSF.
    from vissim.optics.blur.device import convolve_padded
    from vissim.optics.psf.compute import PSF

    device = ArrayBackend("numpy-as-device", np, scipy.fft)
    rng = np.random.default_rng(3)
    planes = rng.random((2, 32, 32), dtype=np.float32)
    for width in range(1, 13):
        kernel = np.zeros((9, 9))
        kernel[4, 4 - width // 3 : 5 + width // 3] = 1.0
        kernel[4 - width % 4 : 5 + width % 4, 4] += 1.0
        psf = PSF.from_array(kernel / kernel.sum(), arcmin_per_px=1.0)
        expected = convolve_padded(planes, psf)
        np.testing.assert_allclose(convolve_padded(planes, psf, device), expected, atol=1e-6)
        del psf
