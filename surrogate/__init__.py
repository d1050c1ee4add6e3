"""Torch/Lightning surrogate mapping vibration features to wear depth (thesis 4; issue 6).

Nothing lives here yet: the surrogate is built on the dataset generator, which comes first.
"""
