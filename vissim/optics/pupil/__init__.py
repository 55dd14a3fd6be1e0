"""The pupil function: the wavefront over the pupil, and the pupil sampled for the PSF.

OSA Zernike polynomials (`zernike`), Zernike wavefronts over a stated pupil and their conversion
to and from prescriptions (`wavefront`), wavefronts given as sampled OPD maps (`opd_map`), one
wavefront per wavelength (`spectral_wavefront`), and the pupil sampled as cell averages for wave
optics (`grid`) and as a stratified grid of rays for geometric optics (`rays`). Importing this
package imports none of its modules.
"""
