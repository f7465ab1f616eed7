"""Kinetostatic stiffness: frame models of mechanisms at a pose (model), the NumPy reference solver (solve),
shared material/section/load options (sections). See docs/stiffness.md."""
