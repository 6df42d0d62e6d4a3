"""The CDR fixtures in tests/data/cdr/ are what real rclpy produces (Rust decodes the same files)."""

import importlib.util
from pathlib import Path

import pytest
from rclpy.serialization import deserialize_message, serialize_message

CDR_DIR = Path(__file__).resolve().parents[1] / "data" / "cdr"

_spec = importlib.util.spec_from_file_location("cdr_generate", CDR_DIR / "generate.py")
generate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(generate)

NAMES = sorted(generate.FIXTURES)


def test_every_committed_fixture_has_a_generator():
    committed = sorted(p.stem for p in CDR_DIR.glob("*.cdr"))
    assert committed == NAMES


@pytest.mark.parametrize("name", NAMES)
def test_fixture_is_byte_identical_to_fresh_rclpy_output(name):
    fresh = generate.serialize(generate.FIXTURES[name]())
    committed = (CDR_DIR / f"{name}.cdr").read_bytes()
    assert fresh == committed, f"regenerate with: .venv/bin/python {CDR_DIR / 'generate.py'}"


@pytest.mark.parametrize("name", NAMES)
def test_fixture_decodes_in_rclpy_to_the_same_message(name):
    """rclpy reads the committed bytes (padding zeroed) back into the message they came from."""
    msg = generate.FIXTURES[name]()
    data = (CDR_DIR / f"{name}.cdr").read_bytes()
    assert data[:4] == b"\x00\x01\x00\x00"  # encapsulation: CDR, little-endian
    decoded = deserialize_message(data, type(msg))
    # Compare through the bytes: NaN ranges make message equality false by definition.
    assert generate.serialize(decoded) == data


def test_zero_padding_clears_only_alignment_gaps():
    """rclpy's raw bytes and the fixture differ at most in padding bytes, which are zero."""
    for name in NAMES:
        msg = generate.FIXTURES[name]()
        raw = serialize_message(msg)
        clean = generate.zero_padding(raw, type(msg))
        assert len(raw) == len(clean), name
        for offset, (a, b) in enumerate(zip(raw, clean, strict=True)):
            assert a == b or b == 0, f"{name}: byte {offset} changed to {b}"
    # A string of 4 chars + NUL leaves 3 padding bytes before a double; a truncated body fails.
    with pytest.raises(ValueError):
        generate.zero_padding(serialize_message(generate.header())[:-1], type(generate.header()))
