"""CLI command groups. Each module registers its commands on ``scalesynth.cliapp.app`` when imported (import
``app`` and the shared helpers from ``scalesynth.cliapp``, never from ``scalesynth.cli``, which loads these modules)."""
