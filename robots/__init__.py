"""Data package ``seds_casadi._robots``: the shipped URDFs and their sources (README.md here),
found with ``importlib.resources``."""
