"""Triangle meshes of a field for exudyn's contact: the surface z = H(x, y) and the walls."""

from __future__ import annotations

import numpy as np

from ..minigolf.fields import Field

__all__ = ["field_mesh", "wall_mesh", "MAX_TRIANGLES"]

#: the most triangles a field mesh may have (the contact search slows down beyond)
MAX_TRIANGLES = 60_000


def field_mesh(field: Field, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Triangle mesh of the field's surface over its bounds: points (n, 3), triangles (m, 3)
    with normals pointing up.

    ``spacing`` [m] defaults to 3 cm on curved fields and to the whole field on a plane.
    Raises ``ValueError`` when the mesh would exceed :data:`MAX_TRIANGLES`.
    """
    b = field.bounds
    if spacing is None:
        spacing = max(b[1] - b[0], b[3] - b[2]) if field.surface.shape == "plane" else 0.03
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be positive, got {spacing}")
    nx = max(2, int(np.ceil((b[1] - b[0]) / spacing)) + 1)
    ny = max(2, int(np.ceil((b[3] - b[2]) / spacing)) + 1)
    n_trig = 2 * (nx - 1) * (ny - 1)
    if n_trig > MAX_TRIANGLES:
        raise ValueError(f"a {spacing:g} m mesh of the field {field.name!r} has {n_trig} "
                         f"triangles, more than the {MAX_TRIANGLES} the contact solver handles "
                         f"here: use a larger spacing (at least "
                         f"{spacing * np.sqrt(n_trig / MAX_TRIANGLES):.3f} m)")
    xs, ys = np.linspace(b[0], b[1], nx), np.linspace(b[2], b[3], ny)
    X, Y = np.meshgrid(xs, ys)  # rows along y
    P = np.column_stack([X.ravel(), Y.ravel()])
    pts = np.column_stack([P, field.surface.height(P)])
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (j * nx + i).ravel()
    tri = np.concatenate([np.column_stack([a, a + 1, a + nx + 1]),
                          np.column_stack([a, a + nx + 1, a + nx])])
    return pts, tri


def wall_mesh(field: Field, height: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Vertical strips along the bounds, from below the lowest to ``height`` above the highest
    point of the surface along each side; points (16, 3), triangles (8, 3) with normals
    pointing into the field."""
    b = field.bounds
    corners = [(b[0], b[2]), (b[1], b[2]), (b[1], b[3]), (b[0], b[3])]
    pts, tri = [], []
    for k in range(4):
        (x0, y0), (x1, y1) = corners[k], corners[(k + 1) % 4]
        s = np.linspace(0, 1, 200)[:, None]
        h = field.surface.height((1 - s) * np.array([x0, y0]) + s * np.array([x1, y1]))
        z0, z1 = float(h.min()) - 0.05, float(h.max()) + height
        base = len(pts)
        pts += [(x0, y0, z0), (x1, y1, z0), (x1, y1, z1), (x0, y0, z1)]
        # counter-clockwise corners: (p1 - p0) x (p2 - p0) points inwards for (0, 2, 1)
        tri += [(base, base + 2, base + 1), (base, base + 3, base + 2)]
    return np.array(pts, float), np.array(tri, int)
