"""The paper's point maze as a layout: the map, its start and goal cells, its walls as rectangles
and its two routes, which the simulation builds and the evaluation measures paths against.

The authors' prototype: 1 m cells, 11 rows × 8 columns with the border wall, y up, row 0 at the
bottom, cell centres x = col − 3.5, y = row − 5 (:data:`MAZE_MAP`). The ball starts at the centre
of one of the six S cells, the goal is the centre of one of the three G cells; the left one-cell
corridor beside the internal wall is the narrow route, the three-cell-wide right side the wide
one.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .world import Rect, rect_distance

MAZE_MAP = (
    "########",  # row 10
    "#GG....#",
    "#G.....#",
    "#......#",
    "#.##...#",
    "#.##...#",
    "#.##...#",
    "#......#",
    "#......#",
    "#SSSSSS#",
    "########",  # row 0
)
"""The maze, top row first: ``#`` wall, ``S`` start cell, ``G`` goal cell, ``.`` free."""


XY = tuple[float, float]
"""A point in the plane, (x, y), metres."""


@dataclass(frozen=True)
class MazeConfig:
    """One episode's start and goal, the centres (x, y) of an S and a G cell."""

    start: XY
    goal: XY


@dataclass(frozen=True)
class MazeLayout:
    """The maze as geometry (metres, world frame): what the simulation builds and the evaluation
    measures paths against."""

    walls: tuple[Rect, ...]
    """Wall rectangles: runs of wall cells, merged across rows where they line up."""
    bounds: Rect
    """The free area inside the border wall."""
    starts: tuple[XY, ...]
    """Centres of the start cells, left to right."""
    goals: tuple[XY, ...]
    """Centres of the goal cells, bottom row first, left to right."""
    narrow_route: Rect
    """The free strip between the internal wall and the border on its narrower side."""
    wide_route: Rect
    """The free strip on the internal wall's other side."""

    @classmethod
    def from_map(cls, rows: tuple[str, ...]) -> MazeLayout:
        """The layout of a map drawn as :data:`MAZE_MAP` is (1 m cells, centred on the origin,
        a one-cell border wall and one internal wall block)."""
        n_rows, n_cols = len(rows), len(rows[0])
        x_min, y_min = -n_cols / 2, -n_rows / 2
        runs: list[list[int]] = []  # [c0, c1, r0, r1], cells c0..c1−1 of rows r0..r1−1
        cells: dict[str, list[XY]] = {"S": [], "G": []}
        for r in range(n_rows):
            line = rows[n_rows - 1 - r]
            for m in re.finditer("#+", line):
                run = next((w for w in runs if w[:2] == [m.start(), m.end()] and w[3] == r), None)
                if run is None:
                    runs.append([m.start(), m.end(), r, r + 1])
                else:
                    run[3] = r + 1
            for c, ch in enumerate(line):
                if ch in cells:
                    cells[ch].append((x_min + c + 0.5, y_min + r + 0.5))
        walls = tuple((x_min + c0, y_min + r0, x_min + c1, y_min + r1) for c0, c1, r0, r1 in runs)
        bounds = (x_min + 1, y_min + 1, -x_min - 1, -y_min - 1)
        inner = [w for w, (c0, c1, r0, r1) in zip(walls, runs, strict=True)
                 if c0 > 0 and c1 < n_cols and r0 > 0 and r1 < n_rows]  # fmt: skip
        if len(inner) != 1:
            raise ValueError(f"expected one internal wall block, found {len(inner)}")
        bx0, by0, bx1, by1 = inner[0]
        left, right = (bounds[0], by0, bx0, by1), (bx1, by0, bounds[2], by1)
        narrow, wide = (left, right) if bx0 - bounds[0] <= bounds[2] - bx1 else (right, left)
        return cls(walls, bounds, tuple(cells["S"]), tuple(cells["G"]), narrow, wide)

    def configurations(self) -> list[MazeConfig]:
        """Every start × goal combination, starts outer, each in the layout's order.

        The narrow route is the shorter one (taut-string lengths) only from the left: by 0.8 to
        2.6 m from the starts x = −2.5 and −1.5, by 0–1.1 m from x = −0.5; from x = 0.5 the two
        are within 0.7 m either way, and from x ≥ 1.5 the wide route is shorter by 0.2 to 1.8 m.
        """
        return [MazeConfig(s, g) for s in self.starts for g in self.goals]

    def clearance(self, xy) -> float:
        """Distance (m) from a point to the nearest wall (negative inside one)."""
        x, y = float(xy[0]), float(xy[1])
        return min(rect_distance(x, y, w) for w in self.walls)

    def route_taken(self, xy_path) -> str:
        """Which route a path of (x, y) points took: ``"narrow"`` or ``"wide"`` for the route
        whose strip beside the internal wall it was in last, ``"neither"`` if it entered neither.

        "Last" makes a path that looked into one route and turned back count for the other, and
        one that crashed inside a route count for that route.
        """
        strips = {"narrow": self.narrow_route, "wide": self.wide_route}
        route = "neither"
        for x, y in np.asarray(xy_path, dtype=float).reshape(-1, 2):
            for name, (x0, y0, x1, y1) in strips.items():
                if x0 <= x <= x1 and y0 <= y <= y1:
                    route = name
        return route


LAYOUT = MazeLayout.from_map(MAZE_MAP)
"""The prototype's maze."""

# The layout's answers as plain functions, for the evaluation code.
configurations = LAYOUT.configurations
route_taken = LAYOUT.route_taken
