"""The paper's drone world — the arena's geometry, the ranges its random arenas are drawn from,
the LiDAR — as ``data/paper_world.json`` states it.

That file is the repository's ``config/paper_world.json``, which the Rust core compiles in
(``cstep_core::arena::PAPER_WORLD``): one statement of the setting for both sides, so the
simulation the agents fly in and the scans the scorer models cannot drift apart.
"""

from __future__ import annotations

import json
from typing import Any

from ..resources import PACKAGE

PAPER_WORLD_FILE = PACKAGE / "data" / "paper_world.json"
"""Where the package keeps the file."""

PAPER_WORLD: dict[str, Any] = json.loads(PAPER_WORLD_FILE.read_text())
"""The file's contents: ``arena`` (``bounds``, ``block_x``, ``block_width``, ``height``,
``altitude``, ``start``, ``goal``, ``draws``) and ``lidar`` (``beams``, ``range_min``,
``range_max``), metres."""
ARENA: dict[str, Any] = PAPER_WORLD["arena"]
"""The arena's section."""
LIDAR: dict[str, Any] = PAPER_WORLD["lidar"]
"""The LiDAR's section."""
