"""The simulation flies the robot the scorer models: the Python side's reading of a URDF
(``DroneParams.from_urdf``) and the Rust core's (``cstep_scoring.robot_description``, the
function the node and the in-process scorer use) agree on the shipped Crazyflie and on variants
that exercise each rule — masses summed over all links, the base link found as the one that is
no joint's child whatever its name, the collision radius from the base link's shapes and their
offsets — and on gravity."""

import re

import cstep_scoring
import pytest
from cstep_bridge.resources import drone_urdf
from cstep_bridge.sim.drone import DroneParams, G

SHIPPED = drone_urdf().read_text()


def variant(**changes: str) -> str:
    """The shipped URDF with each ``old=new`` regular-expression substitution applied once."""
    text = SHIPPED
    for old, new in changes.values():
        text, count = re.subn(old, new, text, count=1)
        assert count == 1, old
    return text


VARIANTS = {
    "shipped": SHIPPED,
    # Before the Python side summed the links, it read the body's mass alone (0.027 kg).
    "rotor masses": SHIPPED.replace('<mass value="0"/>', '<mass value="0.001"/>'),
    # Before it found the base link by structure, it looked for a link named "body".
    "base link renamed": SHIPPED.replace('"body"', '"base_link"'),
    "other constants": variant(
        kf=(r'kf="[^"]*"', 'kf="4.1e-10"'),
        arm=(r'arm="[^"]*"', 'arm="0.05"'),
        t2w=(r'thrust2weight="[^"]*"', 'thrust2weight="3.1"'),
        ixx=(r'ixx="[^"]*"', 'ixx="2.5e-05"'),
    ),
    "wider collision cylinder": variant(radius=(r'radius="0.06"', 'radius="0.08"')),
}


@pytest.mark.parametrize("name", VARIANTS)
def test_python_and_the_core_read_the_same_drone(name, tmp_path):
    path = tmp_path / "drone.urdf"
    path.write_text(VARIANTS[name])
    ours = DroneParams.from_urdf(path)
    core = cstep_scoring.robot_description(str(path))
    assert core == cstep_scoring.robot_description(VARIANTS[name])  # path or text alike
    assert ours.mass == pytest.approx(core["mass"], rel=1e-12)
    assert ours.inertia == pytest.approx(core["inertia"], rel=1e-12)
    assert (ours.kf, ours.km, ours.arm, ours.thrust2weight) == pytest.approx(
        (core["kf"], core["km"], core["arm"], core["thrust2weight"]), rel=1e-12
    )
    assert ours.radius == pytest.approx(core["collision_radius"], rel=1e-12)
    assert core["gravity"] == G


def test_a_urdf_the_core_refuses_is_an_error_naming_it(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text(SHIPPED.replace('<mass value="0.027"/>', '<mass value="-1"/>'))
    with pytest.raises(ValueError, match="mass"):
        cstep_scoring.robot_description(str(path))
