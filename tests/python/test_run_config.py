"""A run's configuration (:class:`~cstep_bridge.training.config.RunConfig`) has one set of names:
``run.json``'s keys, the trainer's options and a protocol's settings; every committed ``run.json``,
of whatever age, still reads."""

import dataclasses
import json

import pytest
from conftest import REPO
from cstep_bridge.errors import ConfigError
from cstep_bridge.training import protocol
from cstep_bridge.training.config import RunConfig
from cstep_bridge.training.trainer import parse_args, run_settings

COMMITTED = sorted((REPO / "experiments").rglob("run.json"))


def test_a_protocols_settings_are_fields_of_the_run_configuration():
    fields = [f.name for f in dataclasses.fields(RunConfig)]
    assert set(protocol.SETTING_NAMES) <= set(fields)
    for name in protocol.PROTOCOLS:
        assert set(protocol.settings(protocol.load(name, "drone"))) == set(protocol.SETTING_NAMES)


@pytest.mark.parametrize("option", ["--safety-coefficient", "--c"])
def test_the_safety_coefficient_option_and_its_old_alias_set_the_field(option):
    args = parse_args(["--agent", "empowered", option, "0.5", "--out", "x"])
    assert run_settings(args).safety_coefficient == 0.5


def test_every_committed_run_json_reads_and_writes_back_the_same(tmp_path):
    assert len(COMMITTED) > 20
    for path in COMMITTED:
        stored = json.loads(path.read_text())
        config = RunConfig.from_json(stored)
        assert config.safety_coefficient == stored["c"], path
        assert config.env == stored["env"] and config.seed == stored["seed"], path
        config.save(tmp_path)
        again = RunConfig.load(tmp_path)
        assert again == config, path
        assert "c" not in json.loads((tmp_path / "run.json").read_text())


def test_an_old_run_json_takes_what_its_run_trained_with():
    stored = json.loads(COMMITTED[0].read_text())
    old = {k: v for k, v in stored.items() if k not in ("reward_source", "observation", "n_envs")}
    config = RunConfig.from_json(old)
    assert (config.reward_source, config.observation, config.n_envs) == ("node", "raw", None)


def test_a_run_json_with_a_key_it_does_not_know_is_refused():
    stored = {**json.loads(COMMITTED[0].read_text()), "colour": "blue"}
    with pytest.raises(ConfigError, match="colour"):
        RunConfig.from_json(stored)
