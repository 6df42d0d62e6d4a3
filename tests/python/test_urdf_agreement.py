"""The simulation flies the robot the scorer models: the Python side's reading of a URDF
(``DroneParams.from_urdf``) and the Rust core's (``cstep_scoring.robot_description``, the
function the node and the in-process scorer use) agree on the shipped Crazyflie and on variants
that exercise each rule — masses summed over all links, the base link found as the one that is
no joint's child whatever its name, the collision radius from the base link's shapes and their
offsets — and on gravity. Likewise the Husky's drive (``HuskyParams.from_urdf`` against
``cstep_scoring.wheeled_description``): wheels, track, the skid steer's effective track, extent."""

import re

import cstep_scoring
import pytest
from cstep_bridge.resources import drone_urdf
from cstep_bridge.sim.drone import DroneParams, G
from cstep_bridge.sim.husky import HUSKY_URDF, HuskyParams

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


HUSKY = HUSKY_URDF.read_text()

HUSKY_VARIANTS = {
    "shipped": HUSKY,
    "bigger wheels": HUSKY.replace('radius="0.17775"', 'radius="0.2"'),
    "wider track": HUSKY.replace('xyz="0.256 0.2854 0.03282"', 'xyz="0.256 0.31 0.03282"'),
    # Two wheels a side make a skid steer; with the rear ones welded it is a differential
    # drive, which turns on its geometric track.
    "rear wheels welded": HUSKY.replace(
        '<joint name="rear_left_wheel" type="continuous">',
        '<joint name="rear_left_wheel" type="fixed">',
    ).replace(
        '<joint name="rear_right_wheel" type="continuous">',
        '<joint name="rear_right_wheel" type="fixed">',
    ),
}


@pytest.mark.parametrize("name", HUSKY_VARIANTS)
def test_python_and_the_core_read_the_same_wheeled_robot(name, tmp_path):
    text = HUSKY_VARIANTS[name]
    if name != "shipped":
        assert text != HUSKY, "the variant changed nothing"
    path = tmp_path / "husky.urdf"
    path.write_text(text)
    ours = HuskyParams.from_urdf(path)
    core = cstep_scoring.wheeled_description(str(path))
    assert core == cstep_scoring.wheeled_description(text)  # path or text alike
    assert ours.wheel_radius == pytest.approx(core["wheel_radius"], rel=1e-12)
    assert ours.track == pytest.approx(core["track"], rel=1e-12)
    assert ours.separation_multiplier == core["separation_multiplier"]
    assert ours.effective_track == pytest.approx(core["effective_track"], rel=1e-12)
    assert (list(ours.left_joints), list(ours.right_joints)) == (
        core["left_joints"],
        core["right_joints"],
    )
    assert ours.half_width == pytest.approx(max(core["outline_y"][1], -core["outline_y"][0]))
    assert ours.chassis_top == pytest.approx(core["outline_z"][1], rel=1e-12)


def test_a_urdf_without_wheels_is_refused_by_the_cores_wheeled_reading():
    with pytest.raises(ValueError, match="looked for continuous or revolute joints"):
        cstep_scoring.wheeled_description(SHIPPED)  # the Crazyflie
