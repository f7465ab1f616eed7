"""The evaluation pipeline, one job per module: grid geometry (grid), evaluation plans (plans), the adaptive column
evaluator over a population (adaptive), strategy choice under a tolerance (strategy), metric assembly (assembly), the
report API (report) and config adapters (configs). ``scalesynth.evaluate`` re-exports the public names. Nothing
here names a mechanism: each mechanism carries its own plans (``Mechanism.node_plan`` and friends)."""
