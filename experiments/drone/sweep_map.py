"""Where every drone run of the sweep landed against the issue's bar: success against collisions on
the 100 evaluation arenas, one point per run, read from the run tables of the sweep's full
record (the notebook before it was trimmed, ``git show f9ed875:experiments/protocol.md``; no
flights, no training).

    PYTHONPATH=py_bridge .venv/bin/python experiments/drone/sweep_map.py --out experiments/drone/sweep_map.png

A run counts when it has a row in a run table whose last column is the 100-arena result (``100
arenas succ / coll``, the tables from d35 on; the earlier tables end with the 40-episode
validation instead and are left out, as are runs stopped before an evaluation). Points are
coloured by the sweep's phase (which base the run changed one lever of), so the picture shows
what each phase moved: the bar (≥ 85 % success, ≤ 5 % collisions) is the shaded corner.
"""

from __future__ import annotations

import argparse
import re
import subprocess
from pathlib import Path

ROW = re.compile(r"^\| (d\d{2,3})-[^|]*\|.*\| (\d+(?:\.\d+)?) % / (\d+(?:\.\d+)?) % \|\s*$")
"""A run-table row: its run number, then, in its last cell, success / collisions."""
HEADER = "| run | change |"
"""How a run table's header starts."""
RESULT_COLUMN = "| 100 arenas succ / coll |"
"""How the header of a run table whose last column is the 100-arena result ends."""
RECORD = "f9ed875:experiments/protocol.md"
"""The sweep's full record in git: the notebook with every run table, before it was trimmed."""

PHASES = (
    ("d34–d49: 16 envs, goal curriculum", 34, 49),
    ("d50–d105: reverse curriculum (start moves)", 50, 105),
    ("d106–d109: tuned.yml before 2026-12-05 (goal curriculum, 8 envs)", 106, 109),
    ("d110–d119: reverse curriculum, max_grad_norm 1000", 110, 119),
    ("d120–d133: + log std −2 (d120–d121) or GAE λ 0.9 (d124–d133)", 120, 133),
    ("d134–d137: + noise cap 5 → 0.5", 134, 143),
    ("d144–d151: + curriculum promoting on holding the goal (d150–d151: 2 M steps)", 144, 151),
    ("d152–d155: + GAE λ 0.98", 152, 155),
    ("d156–d163: reverse curriculum, max_grad_norm 1000, 2 M steps", 156, 165),
    ("d166–d169: + curriculum promoting on holding the goal, raw observations", 166, 169),
    ("d170–d179: + γ 0.99", 170, 179),
    ("d180–d189: + gSDE resampled every 4 steps", 180, 189),
    ("d190–d199: + minibatches of 1 024", 190, 199),
    ("d200–d209: + minibatches of 128", 200, 209),
    ("d210–d219: + learning rate from 2e-4", 210, 219),
    ("d220–d229: + a 512-512 network", 220, 229),
    ("d230–d239: + γ 0.998", 230, 239),
    ("d240–d249: + n_steps 128", 240, 249),
    ("d250–d259: + n_steps 512 (tuned.yml since their read)", 250, 259),
    ("d260–d269: tuned.yml + n_steps 1024", 260, 269),
    ("d270–d279: tuned.yml + clip range 0.2", 270, 279),
    ("d280–d289: tuned.yml over 2 M steps", 280, 289),
    ("d290–d297: tuned.yml + curriculum promoting at 80 %", 290, 299),
    ("d300–d305: tuned.yml + 5 epochs", 300, 309),
)
"""The sweep's phases by run number: (label, first, last); a run in none stops the script, so each
new screen adds its phase here."""

BAR_SUCCESS, BAR_COLLISIONS = 85.0, 5.0
"""The issue's drone bar, in percent of the 100 arenas."""
MARKERS = "os^Dv"
"""Marker shapes the phases cycle through beside their colours."""


def runs(record: str) -> dict[str, tuple[float, float]]:
    """Run number → (success %, collisions %) on the 100 arenas; a run listed twice (a result table
    and the sweep table) keeps its last row."""
    found: dict[str, tuple[float, float]] = {}
    in_result_table = False
    for line in record.splitlines():
        if line.startswith(HEADER):
            in_result_table = line.rstrip().endswith(RESULT_COLUMN)
        m = ROW.match(line)
        if m and in_result_table:
            found[m.group(1)] = (float(m.group(2)), float(m.group(3)))
    return found


def by_phase(found: dict[str, tuple[float, float]]) -> dict[str, list[str]]:
    """Phase label → its runs among ``found``, in run order (phases without runs left out)."""
    groups: dict[str, list[str]] = {}
    for run in sorted(found):
        n = int(run[1:])
        label = next((label for label, first, last in PHASES if first <= n <= last), None)
        if label is None:
            raise SystemExit(f"{run}: in no phase of {PHASES}")
        groups.setdefault(label, []).append(run)
    return groups


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--protocol", type=Path, help=f"the record as a file (default: git's {RECORD})")
    ap.add_argument("--out", type=Path, default=Path("experiments/drone/sweep_map.png"))
    args = ap.parse_args()
    if args.protocol:
        source, record = str(args.protocol), args.protocol.read_text()
    else:
        source = RECORD
        record = subprocess.run(
            ["git", "show", RECORD], capture_output=True, text=True, check=True
        ).stdout
    found = runs(record)
    if not found:
        raise SystemExit(f"{source}: no run rows with a 100-arena result")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(11.5, 6))
    ax.add_patch(
        plt.Rectangle(
            (0, BAR_SUCCESS), BAR_COLLISIONS, 100 - BAR_SUCCESS, color="tab:green", alpha=0.2
        )
    )
    ax.text(0.5, 93, "issue's bar", color="tab:green", fontsize=9)
    colors = plt.get_cmap("tab20").colors
    for i, (label, members) in enumerate(by_phase(found).items()):
        xs = [found[r][1] for r in members]
        ys = [found[r][0] for r in members]
        # More phases than a colour cycle: colour and marker together tell them apart.
        style = {"color": colors[i % len(colors)], "marker": MARKERS[i % len(MARKERS)]}
        ax.scatter(xs, ys, label=f"{label} ({len(members)})", s=28, **style)
        for r, x, y in zip(members, xs, ys, strict=True):
            ax.annotate(r, (x, y), fontsize=6, xytext=(2, 2), textcoords="offset points")
    ax.set_xlabel("collisions on the 100 arenas (%)")
    ax.set_ylabel("success on the 100 arenas (%)")
    ax.set_xlim(-2, max(50.0, max(c for _, c in found.values()) + 5))
    ax.set_ylim(-2, 100)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.set_title("Drone sweep: every evaluated run (unempowered, the sweep's record)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}: {len(found)} runs")
    best = max(found, key=lambda r: found[r][0] - found[r][1])
    success, collisions = found[best]
    print(f"largest success − collisions: {best}, {success:g} % − {collisions:g} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
