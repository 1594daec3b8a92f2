"""The published representations the SHRM is compared against and the renderer can draw.

- :mod:`.rsibr` and :mod:`.icosahedron`: Cabral, Olano & Nemec 1999, *Reflection Space Image
  Based Rendering* (twelve prefiltered maps at the icosahedron's vertices, spherical
  barycentric blending).
- Kautz & McCool 2000: the azimuth-free (q = 0) SHRM, ``prefilter(..., azimuth_free=True)``.
- :mod:`.gaussian_lobes` and :mod:`.selfshadow`: Green, Kautz & Durand 2007, *Efficient
  Reflectance and Visibility Approximations for Environment Map Rendering* (K Gaussian
  lobes per view elevation over a spherical-Gaussian mip stack; per-vertex SH visibility).

And the angular-domain methods the SHRM's speed is measured against (``benchmarks/prefilter_speed.py``):

- :mod:`.lobe_truncated`: RH02 Table 4's baseline, the angular sum over only the environment
  pixels where the BRDF lobe exceeds 1e-3 of its peak (a cone about R per view elevation).
- :mod:`.split_sum`: the engines' split-sum approximation for GGX materials (Karis 2013;
  Lagarde & de Rousiers 2014): a GGX-prefiltered map per roughness and the 2-D
  environment-BRDF table.
"""
