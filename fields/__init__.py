"""Data package ``seds_casadi._fields``: the shipped field files (JSON), found with
``importlib.resources``; copy one to make a field of your own (format in README.md here)."""
