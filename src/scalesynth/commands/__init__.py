"""CLI command groups. Each module registers its commands on ``scalesynth.cli.app`` when imported."""
