"""Where and how the optics' numerical work runs, shared by the PSF, blur and depth stages.

`array_backend`: NumPy on the CPU or CuPy on a CUDA GPU (the optional GPU path); `threads`: how
many cores this process may use, with OpenBLAS's own threads held at one; `workspace`: scratch
arrays reused across calls, one set per thread. Importing this package imports none of its
modules.
"""
