"""Data package ``seds_casadi.data``: the shipped putting demonstrations."""
