"""scalesynth: multi-objective dimensional (scale) synthesis of parallel mechanisms."""

__version__ = "0.1.0"
