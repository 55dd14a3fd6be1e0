"""Images blurred by PSFs, in linear light.

`convolve`: one PSF (or one per channel) by FFT convolution (`blur_image`); `device`: the same on
the CPU or a CUDA GPU (`blur_image_on`); `field_dependent`: spatially variant blur from PSFs known
on a grid of nodes; `resample`: images resampled by a lens's magnification and integrated onto
coarser pixels. Importing this package imports none of its modules.
"""
