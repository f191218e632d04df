"""Reconstruction-quality oracles: capture poses + the true ship mesh -> error, completeness, failed?

``scene.make_oracle(section, kind)`` gives the synthetic MVS oracle (default, campaign speed) or the pycolmap
photogrammetric one (validation; ``pip install .[photogrammetry]``). See README.md.

The package itself imports nothing: the experiment config imports ``recon.config``, and the oracles' open3d
costs ~1 s at every start-up and worker spawn.
"""
