"""A small z-buffer rasteriser for object pictures: shaded meshes with correctly hidden marks.

matplotlib's ``mplot3d`` sorts whole artists by depth, so a point behind a mesh can be drawn over
it; a per-pixel depth buffer cannot make that mistake. This module projects a triangle mesh with a
fixed orthographic camera, fills a depth buffer and a Lambert-shaded RGBA image (pure numpy, no
OpenGL, no display), and answers depth tests for points and segments against that buffer, so the
caller draws only what the mesh does not hide.

Conventions: world coordinates in metres; the view's ``rotation`` rows are the camera's right,
up and forward (into the scene) axes; image pixels are (column, row) with row 0 at the top and
pixel centres at half-integers; depth is the coordinate along forward [m] (larger = farther).

Example:
    >>> import numpy as np
    >>> view = fit_view(np.array([[0, 0, 0], [1, 1, 0.0]]), look(0.0, 90.0), 64, 64)
    >>> image = render_mesh(np.eye(3), np.array([[0, 1, 2]]), view)
    >>> image.rgba.shape
    (64, 64, 4)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Most candidate (triangle, pixel) pairs held at once: bounds the memory of one batch (~100 MB).
BATCH_CANDIDATES = 2_000_000
#: Light from the upper left, a little in front of the object, in view axes (right, up, forward).
LIGHT = (-0.45, 0.55, -0.70)
AMBIENT = 0.35
DIFFUSE = 0.65
OUTLINE = (0.25, 0.25, 0.28)


def look(azimuth: float, elevation: float, up: ArrayLike = (0.0, 0.0, 1.0)) -> NDArray[np.float64]:
    """Camera axes for a view from ``azimuth`` around ``up`` and ``elevation`` above its plane.

    Args:
        azimuth: Angle of the camera around the up axis [deg]; for the default z-up, 0 = looking
            from +x. For another up axis the azimuth is measured in the cyclic frame
            (up = y: from +z; up = x: from +y).
        elevation: Angle of the camera above the plane normal to ``up`` [deg], in (-90, 90];
            90 looks down ``-up``.
        up: The world direction shown as "up" in the picture, shape (3,) (normalised here).

    Returns:
        Rotation, shape (3, 3): rows right, up, forward (unit, orthogonal; as a frame
        left-handed, since forward points into the scene).
    """
    a, e = np.radians(azimuth), np.radians(elevation)
    towards_camera = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    forward = -towards_camera
    # Straight down, "up" in the picture is the +y world axis rotated by the azimuth.
    world_up = np.array([0.0, 0.0, 1.0]) if abs(np.sin(e)) < 0.999 else np.array([-np.cos(a), -np.sin(a), 0.0])
    right = np.cross(forward, world_up)
    right /= np.linalg.norm(right)
    z_up = np.stack([right, np.cross(right, forward), forward])
    return z_up @ up_frame(up).T


def up_frame(up: ArrayLike) -> NDArray[np.float64]:
    """A right-handed frame whose third axis is ``up``, shape (3, 3): columns x', y', up.

    For a coordinate axis it is the cyclic permutation (up = +y gives x' = z, y' = x), so views of
    y-up meshes keep the same azimuth meaning whatever the sign conventions of the mesh.
    """
    u = np.asarray(up, dtype=float).reshape(3)
    u = u / np.linalg.norm(u)
    helper = np.zeros(3)
    helper[(int(np.argmax(np.abs(u))) + 1) % 3] = 1.0
    x = helper - (helper @ u) * u
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(u, x), u])


@dataclass(frozen=True)
class View:
    """An orthographic camera fitted to an image.

    Attributes:
        rotation: Rows right, up, forward, shape (3, 3).
        scale: Pixels per metre.
        offset: Pixel position of the world origin's projection, shape (2,) (column, row).
        width: Image width [px].
        height: Image height [px].
    """

    rotation: NDArray[np.float64]
    scale: float
    offset: NDArray[np.float64]
    width: int
    height: int

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """Pixel column, row and depth of world points.

        Args:
            points: World points, shape (n, 3) [m].

        Returns:
            Shape (n, 3): column [px], row [px], depth [m].
        """
        camera = np.asarray(points, dtype=float).reshape(-1, 3) @ self.rotation.T
        column = camera[:, 0] * self.scale + self.offset[0]
        row = -camera[:, 1] * self.scale + self.offset[1]
        return np.column_stack([column, row, camera[:, 2]])


def fit_view(points: ArrayLike, rotation: NDArray[np.float64], width: int, height: int, margin: float = 0.04) -> View:
    """The view that shows every point of ``points``, centred, with a margin.

    Args:
        points: World points that must be in the picture, shape (n, 3) [m].
        rotation: Camera axes from :func:`look`, shape (3, 3).
        width: Image width [px].
        height: Image height [px].
        margin: Free border on each side, as a fraction of the image size.

    Returns:
        The view.
    """
    camera = np.asarray(points, dtype=float).reshape(-1, 3) @ rotation.T
    low, high = camera[:, :2].min(axis=0), camera[:, :2].max(axis=0)
    extent = np.maximum(high - low, 1e-12)
    scale = float(min(width * (1 - 2 * margin) / extent[0], height * (1 - 2 * margin) / extent[1]))
    centre = (low + high) / 2
    offset = np.array([width / 2 - centre[0] * scale, height / 2 + centre[1] * scale])
    return View(np.asarray(rotation, dtype=float), scale, offset, int(width), int(height))


@dataclass(frozen=True)
class Raster:
    """A rendered mesh.

    Attributes:
        rgba: Shaded image, shape (height, width, 4), floats in [0, 1]; background alpha 0.
        depth: Depth of the nearest surface per pixel [m], shape (height, width); inf where empty.
        view: The camera it was rendered with.
    """

    rgba: NDArray[np.float64]
    depth: NDArray[np.float64]
    view: View

    def over(self, other: Raster) -> Raster:
        """This picture and ``other`` (same view) merged per pixel by depth: the nearer surface wins.

        Rendering the object and the hand as separate meshes keeps one colour per mesh and still
        hides each behind the other correctly, as one scene would.
        """
        nearer = self.depth <= other.depth
        rgba = np.where(nearer[..., None], self.rgba, other.rgba)
        return Raster(rgba, np.minimum(self.depth, other.depth), self.view)

    def visible(self, points: ArrayLike, tolerance: float = 0.0) -> NDArray[np.bool_]:
        """Whether each point is in front of (or on) the surface drawn at its pixel.

        Args:
            points: World points, shape (n, 3) [m].
            tolerance: Depth slack [m] for points that lie on the surface; one pixel's worth of
                depth is always added, since a pixel holds the depth at its centre only.

        Returns:
            Shape (n,): True where nothing of the mesh hides the point (outside the image: True).
        """
        projected = self.view.project(points)
        column = np.floor(projected[:, 0]).astype(int)
        row = np.floor(projected[:, 1]).astype(int)
        inside = (column >= 0) & (column < self.view.width) & (row >= 0) & (row < self.view.height)
        surface = np.full(len(projected), np.inf)
        surface[inside] = self.depth[row[inside], column[inside]]
        slack = tolerance + 1.5 / self.view.scale
        return np.asarray(projected[:, 2] <= surface + slack)

    def visible_runs(
        self, start: ArrayLike, end: ArrayLike, tolerance: float = 0.0, samples: int = 48
    ) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """The visible pieces of the segment from ``start`` to ``end``, in pixels.

        Args:
            start: Segment start, shape (3,) [m].
            end: Segment end, shape (3,) [m].
            tolerance: Depth slack [m], as in :meth:`visible`.
            samples: Depth tests along the segment (a piece is resolved to 1/samples).

        Returns:
            (first, last) pixel positions, each shape (2,) (column, row), of every visible piece,
            from ``start`` towards ``end``; a piece ending at ``end`` ends exactly there.
        """
        t = np.linspace(0.0, 1.0, samples)
        a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
        points = a + t[:, None] * (b - a)
        shown = self.visible(points, tolerance)
        pixels = self.view.project(points)[:, :2]
        runs = []
        edges = np.flatnonzero(np.diff(np.r_[0, shown.astype(np.int8), 0]))
        for first, stop in zip(edges[::2], edges[1::2], strict=True):
            if stop - first >= 2:  # a single sample has no length to draw
                runs.append((pixels[first], pixels[stop - 1]))
        return runs


def render_mesh(
    vertices: ArrayLike,
    faces: ArrayLike,
    view: View,
    colour: tuple[float, float, float] = (0.78, 0.80, 0.83),
    outline: bool = True,
) -> Raster:
    """Rasterise a triangle mesh with flat Lambert shading and a depth buffer.

    Args:
        vertices: Vertex positions, shape (v, 3) [m].
        faces: Vertex indices per triangle, shape (f, 3).
        view: The camera (:func:`fit_view`).
        colour: Base RGB of the surface, each in [0, 1].
        outline: Darken the silhouette's boundary pixels, so the shape reads on white paper.

    Returns:
        The image and its depth buffer.
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    width, height = view.width, view.height
    projected = view.project(vertices)
    triangles = projected[faces]  # (f, 3 corners, column/row/depth)
    depth = np.full(height * width, np.inf)
    owner = np.full(height * width, -1, dtype=np.int64)
    low = np.floor(triangles[:, :, :2].min(axis=1) - 0.5).astype(np.int64)
    high = np.ceil(triangles[:, :, :2].max(axis=1) - 0.5).astype(np.int64)
    low = np.maximum(low, 0)
    high = np.minimum(high, [width - 1, height - 1])
    size = np.max(high - low + 1, axis=1)
    keep = np.flatnonzero((size > 0) & np.all(high >= low, axis=1))
    # Triangles in buckets of similar pixel size: each bucket is one vectorised pass over a
    # (triangles, side, side) grid, so a 56k-face bunny costs a few numpy calls, not 56k loops.
    bucket = np.ceil(np.log2(np.maximum(size[keep], 1))).astype(int)
    for level in np.unique(bucket):
        side = 1 << int(level)
        members = keep[bucket == level]
        step = max(1, BATCH_CANDIDATES // (side * side))
        for first in range(0, len(members), step):
            _fill(triangles, low, members[first : first + step], side, width, height, depth, owner)
    normals = _face_normals(vertices, faces) @ view.rotation.T
    light = np.asarray(LIGHT) / np.linalg.norm(LIGHT)
    # Two-sided: a mesh seen from inside (an open or inverted one) is still lit, not black.
    shade = AMBIENT + DIFFUSE * np.abs(normals @ light)
    flat = np.zeros((height * width, 4))
    drawn = owner >= 0
    flat[drawn, :3] = np.clip(np.asarray(colour)[None, :] * shade[owner[drawn], None], 0.0, 1.0)
    flat[drawn, 3] = 1.0
    rgba = flat.reshape(height, width, 4)
    if outline:
        mask = drawn.reshape(height, width)
        padded = np.pad(mask, 1)
        neighbours = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
        rgba[mask & ~neighbours, :3] = OUTLINE
    return Raster(rgba, depth.reshape(height, width), view)


def _face_normals(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """Unit normals per face, shape (f, 3); degenerate faces get a zero normal."""
    corners = vertices[faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)


def _fill(
    triangles: NDArray[np.float64],
    low: NDArray[np.int64],
    members: NDArray[np.int64],
    side: int,
    width: int,
    height: int,
    depth: NDArray[np.float64],
    owner: NDArray[np.int64],
) -> None:
    """Depth-test the pixel centres of ``members`` (boxes of at most ``side`` px) into the buffers."""
    grid = np.arange(side)
    columns = low[members, 0, None, None] + grid[None, None, :]  # (t, 1, side)
    rows = low[members, 1, None, None] + grid[None, :, None]  # (t, side, 1)
    x, y = columns + 0.5, rows + 0.5
    corner = triangles[members]  # (t, 3, 3)
    x0, y0 = corner[:, 0, 0, None, None], corner[:, 0, 1, None, None]
    x1, y1 = corner[:, 1, 0, None, None], corner[:, 1, 1, None, None]
    x2, y2 = corner[:, 2, 0, None, None], corner[:, 2, 1, None, None]
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    # Barycentric weights from edge functions; dividing by the signed area accepts both windings.
    safe = np.where(np.abs(area) > 1e-12, area, np.inf)
    w0 = ((x1 - x) * (y2 - y) - (x2 - x) * (y1 - y)) / safe
    w1 = ((x2 - x) * (y0 - y) - (x0 - x) * (y2 - y)) / safe
    w2 = 1.0 - w0 - w1
    inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0) & (np.abs(area) > 1e-12)
    inside &= (columns < width) & (rows < height)
    z = w0 * corner[:, 0, 2, None, None] + w1 * corner[:, 1, 2, None, None] + w2 * corner[:, 2, 2, None, None]
    triangle = np.broadcast_to(members[:, None, None], inside.shape)[inside]
    pixel = np.broadcast_to(rows * width + columns, inside.shape)[inside]
    z = z[inside]
    if not len(pixel):
        return
    # Nearest candidate per pixel within the batch, then against what earlier batches drew.
    order = np.lexsort((z, pixel))
    pixel, z, triangle = pixel[order], z[order], triangle[order]
    first = np.r_[True, pixel[1:] != pixel[:-1]]
    pixel, z, triangle = pixel[first], z[first], triangle[first]
    nearer = z < depth[pixel]
    depth[pixel[nearer]] = z[nearer]
    owner[pixel[nearer]] = triangle[nearer]


def sphere_mesh(centre: ArrayLike, radius: float, rings: int = 8) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A UV sphere, for fingertips and joints.

    Args:
        centre: Centre, shape (3,) [m].
        radius: Radius [m].
        rings: Latitude bands (twice as many longitude segments).

    Returns:
        Vertices, shape (v, 3) [m], and triangles, shape (f, 3).
    """
    latitude = np.linspace(0.0, np.pi, rings + 1)
    longitude = np.linspace(0.0, 2 * np.pi, 2 * rings, endpoint=False)
    lat, lon = np.meshgrid(latitude, longitude, indexing="ij")
    unit = np.stack([np.sin(lat) * np.cos(lon), np.sin(lat) * np.sin(lon), np.cos(lat)], axis=-1)
    vertices = np.asarray(centre, dtype=float) + radius * unit.reshape(-1, 3)
    return vertices, _grid_faces(rings + 1, 2 * rings)


def tube_mesh(
    start: ArrayLike, end: ArrayLike, radius: float, sides: int = 12
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A closed cylinder from ``start`` to ``end`` (a link of a finger, the palm).

    Args:
        start: Centre of one end, shape (3,) [m].
        end: Centre of the other end, shape (3,) [m].
        radius: Radius [m].
        sides: Segments around the axis.

    Returns:
        Vertices, shape (v, 3) [m], and triangles, shape (f, 3).
    """
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    axis = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
    frame = up_frame(axis)
    angle = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = radius * (np.cos(angle)[:, None] * frame[:, 0] + np.sin(angle)[:, None] * frame[:, 1])
    # Rows: start cap centre, start ring, end ring, end cap centre; caps are fans, so the
    # ends are shaded and hide what is inside the tube.
    vertices = np.vstack([a, a + ring, b + ring, b])
    k = np.arange(sides)
    following = (k + 1) % sides
    side = np.vstack(
        [
            np.column_stack([1 + k, 1 + following, 1 + sides + k]),
            np.column_stack([1 + following, 1 + sides + following, 1 + sides + k]),
        ]
    )
    last = 2 * sides + 1
    caps = np.vstack(
        [
            np.column_stack([np.zeros(sides, int), 1 + following, 1 + k]),
            np.column_stack([np.full(sides, last), 1 + sides + k, 1 + sides + following]),
        ]
    )
    return vertices, np.vstack([side, caps]).astype(np.int64)


def merge_meshes(
    parts: list[tuple[NDArray[np.float64], NDArray[np.int64]]],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """One mesh of several (vertices, faces) parts, shapes (v, 3) and (f, 3) as in the parts."""
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.vstack([v for v, _ in parts])
    faces = np.vstack([f + o for (_, f), o in zip(parts, offsets, strict=True)])
    return vertices, faces


def _grid_faces(rows: int, columns: int) -> NDArray[np.int64]:
    """Triangles of a (rows x columns) vertex grid, wrapping around the columns."""
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(columns), indexing="ij")
    here = r * columns + c
    right = r * columns + (c + 1) % columns
    return np.vstack(
        [
            np.column_stack([here.ravel(), right.ravel(), (here + columns).ravel()]),
            np.column_stack([right.ravel(), (right + columns).ravel(), (here + columns).ravel()]),
        ]
    ).astype(np.int64)
