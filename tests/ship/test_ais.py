import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pyais.encode import ais_to_nmea_0183

from wrp_eval.errors import InputError
from wrp_eval.ship.ais import decode_ais, particulars_from_ais
from wrp_eval.ship.derive import TYPE_RATIOS, ship_type_from_ais_code
from wrp_eval.ship.particulars import ShipType

from .conftest import MMSI, type1, type5, type24


def test_type5_multipart_with_position(container_ais):
    assert len(type5()) == 2  # really a multi-part message
    p = particulars_from_ais(container_ais)
    assert (p.length_bp_m, p.breadth_m, p.draft_m) == (140.0, 20.0, 8.5)
    assert p.ship_type is ShipType.CONTAINER and p.mmsi == MMSI and p.name == "TEST SHIP"
    assert p.lat_deg == pytest.approx(54.1, abs=1e-4) and p.lon_deg == pytest.approx(10.2, abs=1e-4)
    assert p.heading_deg == 90.0
    # depth from draught by T/D, superstructure from length by H/L; both reported as derived
    ratios = TYPE_RATIOS[ShipType.CONTAINER]
    assert p.depth_m == pytest.approx(8.5 / ratios.draft_over_depth)
    assert p.superstructure_height_m == pytest.approx(140 * ratios.superstructure_over_length)
    assert p.derived == {"depth_m", "superstructure_height_m"}


def test_vdo_talker_and_overrides_win():
    sentences = [s.replace("!AIVDM", "!AIVDO") for s in type5()]
    sentences = [s[:s.rfind("*") + 1] + f"{_checksum(s):02X}" for s in sentences]
    p = particulars_from_ais(sentences, {"depth_m": 14.0, "draft_m": 9.0}, ship_type=ShipType.TANKER)
    assert p.depth_m == 14.0 and p.draft_m == 9.0 and p.ship_type is ShipType.TANKER
    assert p.derived == {"superstructure_height_m"}


def _checksum(line: str) -> int:
    value = 0
    for ch in line[1:line.rfind("*")].encode():
        value ^= ch
    return value


def test_class_b_type24_parts_a_and_b():
    p = particulars_from_ais(type24())
    assert (p.length_bp_m, p.breadth_m) == (12.0, 4.0)
    assert p.ship_type is ShipType.FISHING and p.name == "B BOAT"
    assert {"depth_m", "draft_m", "superstructure_height_m"} <= p.derived   # 24B has no draught
    assert p.draft_m < p.depth_m


def test_type18_position_and_heading_not_available_uses_course():
    p = particulars_from_ais(type24(mmsi=5) + _type18(mmsi=5))
    assert p.heading_deg == pytest.approx(45.0) and p.lat_deg == pytest.approx(-33.5, abs=1e-4)


def _type18(mmsi):
    from pyais import encode_dict
    return encode_dict({"msg_type": 18, "mmsi": mmsi, "lat": -33.5, "lon": 151.2, "heading": 511, "course": 45.0})


def test_position_of_other_ship_ignored():
    p = particulars_from_ais(type5() + type1(mmsi=999))
    assert p.lat_deg == 0.0 and "lat_deg" not in p.derived


@pytest.mark.parametrize("code,expected", [(30, ShipType.FISHING), (60, ShipType.CRUISE), (69, ShipType.CRUISE),
                                           (70, ShipType.CONTAINER), (79, ShipType.CONTAINER),
                                           (80, ShipType.TANKER), (89, ShipType.TANKER), (52, None), (0, None)])
def test_ship_type_codes(code, expected):
    assert ship_type_from_ais_code(code) is expected


def test_unmapped_code_falls_back_to_stylized_and_says_so():
    p = particulars_from_ais(type5(ship_type=52))
    assert p.ship_type is ShipType.STYLIZED and "ship_type" in p.derived


def test_bad_checksum_names_sentence():
    good = type1()[0]
    bad = good[:-2] + f"{(_checksum(good) + 1) % 256:02X}"
    with pytest.raises(InputError, match=r"sentence 3: checksum mismatch"):
        particulars_from_ais(type5() + [bad])


def test_truncated_payload():
    s5 = type5()
    # re-wrap a type 5 payload cut after 300 bits with a correct checksum: only the length is wrong
    payload = s5[0].split(",")[5] + s5[1].split(",")[5]
    short = ais_to_nmea_0183(payload[:50], "AI", "VDM", "A", 0)
    with pytest.raises(InputError, match=r"sentence 1: truncated payload: message type 5 has 300 bits"):
        particulars_from_ais(short)


def test_missing_fragment_and_missing_static_data():
    with pytest.raises(InputError, match="missing fragment 2 of 2"):
        particulars_from_ais(type5()[:1] + type1())
    with pytest.raises(InputError, match="without its earlier fragments"):
        particulars_from_ais(type5()[1:])
    with pytest.raises(InputError, match="no static data"):
        particulars_from_ais(type1())
    with pytest.raises(InputError, match="no dimensions"):
        particulars_from_ais(type5(to_bow=0, to_stern=0))


def test_garbage_and_several_ships():
    for line, message in [("hello", "not an NMEA sentence"), ("!AIVDM,1,1,,A", "malformed"),
                          ("$GPGGA,1,2*00", "malformed")]:
        with pytest.raises(InputError, match=message):
            particulars_from_ais([line])
    with pytest.raises(InputError, match="several ships"):
        particulars_from_ais(type5() + type5(mmsi=1, seq_id=4))
    with pytest.raises(InputError, match="no AIS sentences"):
        particulars_from_ais(["", "# comment"])


def test_draft_deeper_than_depth_override_is_refused(container_ais):
    with pytest.raises(InputError, match="draft .* must be less than the moulded depth"):
        particulars_from_ais(container_ais, {"depth_m": 8.0})


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.text(max_size=90), min_size=1, max_size=4))
def test_fuzz_random_strings(lines):
    try:
        decode_ais(lines)
    except InputError as err:
        assert "\n" not in str(err)


_VALID = type5() + type1() + type24()


@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(_VALID) - 1), st.integers(0, 200), st.characters(min_codepoint=32, max_codepoint=126),
       st.sampled_from(["replace", "delete", "insert", "truncate"]))
def test_fuzz_mutated_valid_sentences(which, position, char, how):
    lines = list(_VALID)
    s = lines[which]
    i = position % len(s)
    lines[which] = {"replace": s[:i] + char + s[i + 1:], "delete": s[:i] + s[i + 1:],
                    "insert": s[:i] + char + s[i:], "truncate": s[:i]}[how]
    try:
        particulars_from_ais(lines)
    except InputError as err:
        assert "\n" not in str(err)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(_VALID) - 1), st.integers(0, 200), st.characters(min_codepoint=32, max_codepoint=126),
       st.sampled_from(["replace", "delete", "insert", "truncate"]))
def test_fuzz_mutated_payloads_with_valid_checksum(which, position, char, how):
    """Mutations that get past the checksum reach pyais's decoder: still parse or InputError."""
    lines = list(_VALID)
    s = lines[which]
    star = s.rfind("*")
    i = position % star
    body = {"replace": s[:i] + char + s[i + 1:], "delete": s[:i] + s[i + 1:], "insert": s[:i] + char + s[i:],
            "truncate": s[:i] + s[star:]}[how]
    star = body.rfind("*")
    lines[which] = body[:star + 1] + f"{_checksum(body):02X}" if star > 0 else body
    try:
        particulars_from_ais(lines)
    except InputError as err:
        assert "\n" not in str(err)
