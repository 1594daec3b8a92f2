"""The published representations the SHRM is compared against and the renderer can draw.

- :mod:`.rsibr` and :mod:`.icosahedron`: Cabral, Olano & Nemec 1999, *Reflection Space Image
  Based Rendering* (twelve prefiltered maps at the icosahedron's vertices, spherical
  barycentric blending).
- Kautz & McCool 2000: the azimuth-free (q = 0) SHRM, ``prefilter(..., azimuth_free=True)``.
- :mod:`.gaussian_lobes` and :mod:`.selfshadow`: Green, Kautz & Durand 2007, *Efficient
  Reflectance and Visibility Approximations for Environment Map Rendering* (K Gaussian
  lobes per view elevation over a spherical-Gaussian mip stack; per-vertex SH visibility).
"""
