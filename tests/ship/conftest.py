"""Shared fixtures of the ship-stage tests: AIS sentences built with pyais's encoder (valid checksums)."""

from __future__ import annotations

import pytest
from pyais import encode_dict

MMSI = 211234567


def type5(mmsi: int = MMSI, ship_type: int = 70, to_bow: int = 100, to_stern: int = 40, to_port: int = 10,
          to_starboard: int = 10, draught: float = 8.5, seq_id: int = 3, name: str = "TEST SHIP") -> list[str]:
    return encode_dict({"msg_type": 5, "mmsi": mmsi, "shipname": name, "ship_type": ship_type, "to_bow": to_bow,
                        "to_stern": to_stern, "to_port": to_port, "to_starboard": to_starboard,
                        "draught": draught, "callsign": "DABC"}, talker_id="AI", sentence_type="VDM",
                       seq_id=seq_id)


def type1(mmsi: int = MMSI, lat: float = 54.1, lon: float = 10.2, heading: int = 90, course: float = 91.0,
          msg_type: int = 1) -> list[str]:
    return encode_dict({"msg_type": msg_type, "mmsi": mmsi, "lat": lat, "lon": lon, "heading": heading,
                        "course": course}, talker_id="AI", sentence_type="VDM")


def type24(mmsi: int = 338123456, ship_type: int = 30, length=(8, 4), breadth=(2, 2)) -> list[str]:
    part_a = encode_dict({"msg_type": 24, "mmsi": mmsi, "partno": 0, "shipname": "B BOAT"})
    part_b = encode_dict({"msg_type": 24, "mmsi": mmsi, "partno": 1, "ship_type": ship_type,
                          "to_bow": length[0], "to_stern": length[1], "to_port": breadth[0],
                          "to_starboard": breadth[1]})
    return part_a + part_b


@pytest.fixture
def container_ais() -> list[str]:
    """Two-part type 5 (cargo, 140 x 20 m, draught 8.5 m) plus a type 1 position report."""
    return type5() + type1()
