"""Depth-dependent blur: a scene with depth, one eye, one accommodation state.

`depth_map`: an RGB-D image blurred layer by layer (`blur_depth`), with its PSFs and threads
(`psfs`), each layer's matte, continuation behind nearer content and window (`windows`, `pullpush`)
and the near-to-far compositing (`composite`); `layered`: a layered scene whose every layer is
known, hidden parts included (`composite_layers`). Importing this package imports none of its
modules.
"""
