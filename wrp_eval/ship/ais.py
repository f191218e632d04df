"""Ship particulars from raw AIS NMEA 0183 sentences (!AIVDM / !AIVDO), decoded with pyais.

Used messages (ITU-R M.1371): type 5 (class A static and voyage data: dimensions, draught, ship type, name,
MMSI), type 24 parts A (name) and B (ship type, dimensions) for class B, and the position reports of types
1/2/3 (class A) and 18 (class B) for latitude, longitude and heading. Other valid message types are ignored.
Multi-part sentences are assembled by (sequence id, channel). Every problem (bad checksum, truncated payload,
missing fragment, no static data, several ships) is an :class:`InputError` naming the sentence.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from pyais import NMEAMessage
from pyais.exceptions import AISBaseException

from wrp_eval.errors import InputError
from wrp_eval.ship.derive import (
    DIMENSION_FIELDS,
    POSITION_FIELDS,
    complete_particulars,
    ship_type_from_ais_code,
)
from wrp_eval.ship.particulars import ShipParticulars, ShipType

# Minimum payload bits per message type (nominal lengths of ITU-R M.1371; type 5 is nominally 424 bits but
# some transponders drop the last spare bits, so 420 is accepted). Shorter payloads are "truncated".
MIN_PAYLOAD_BITS = {1: 168, 2: 168, 3: 168, 5: 420, 18: 168, (24, 0): 160, (24, 1): 168}
POSITION_TYPES = (1, 2, 3, 18)
HEADING_NOT_AVAILABLE = 511
_PYAIS_ERRORS = (AISBaseException, ValueError, IndexError, KeyError, TypeError, UnicodeError, AttributeError)


@dataclass
class AisReport:
    """What the sentences say about one ship (None: not reported / not available)."""

    mmsi: int | None = None
    name: str = ""
    ship_type_code: int | None = None
    length_m: float | None = None
    breadth_m: float | None = None
    draught_m: float | None = None
    lat_deg: float | None = None
    lon_deg: float | None = None
    heading_deg: float | None = None
    static_from: list[str] = field(default_factory=list)


def _short(line: str, n: int = 48) -> str:
    return repr(line if len(line) <= n else line[:n] + "...")


def _computed_checksum(line: str) -> int | None:
    body = line[1:line.rfind("*")] if "*" in line else None
    if body is None:
        return None
    value = 0
    for ch in body.encode("ascii", errors="replace"):
        value ^= ch
    return value


def _parse_sentence(line: str, label: str) -> NMEAMessage:
    if not line.startswith(("!", "$")):
        raise InputError(label, f"not an NMEA sentence (must start with '!'): {_short(line)}")
    try:
        raw = line.encode("ascii")
    except UnicodeError:
        raise InputError(label, f"non-ASCII characters in {_short(line)}") from None
    try:
        msg = NMEAMessage(raw)
    except _PYAIS_ERRORS as err:
        raise InputError(label, f"malformed AIS sentence {_short(line)}: {type(err).__name__}") from None
    if msg.type not in ("VDM", "VDO"):
        raise InputError(label, f"not an AIVDM/AIVDO sentence (type {msg.type!r}): {_short(line)}")
    if not msg.is_valid:
        computed = _computed_checksum(line)
        raise InputError(label, f"checksum mismatch in {_short(line)}: sentence says {msg.checksum:02X}, "
                                f"computed {computed:02X}" if computed is not None
                         else f"checksum missing in {_short(line)}")
    if not msg.payload:
        raise InputError(label, f"empty payload in {_short(line)}")
    if not (1 <= msg.frag_cnt <= 9 and 1 <= msg.frag_num <= msg.frag_cnt):
        raise InputError(label, f"fragment {msg.frag_num} of {msg.frag_cnt} is not possible: {_short(line)}")
    return msg


def _assemble(sentences: Sequence[str], labels: Sequence[str]) -> list[tuple[NMEAMessage, str]]:
    """Parse every sentence and join multi-part messages; returns (message, label of its first part)."""
    complete: list[tuple[NMEAMessage, str]] = []
    pending: dict[tuple, tuple[list[NMEAMessage], str]] = {}
    for line, label in zip(sentences, labels, strict=True):
        msg = _parse_sentence(line, label)
        if msg.frag_cnt == 1:
            complete.append((msg, label))
            continue
        key = (msg.seq_id, msg.channel, msg.frag_cnt)
        if msg.frag_num == 1:
            if key in pending:
                first_label = pending[key][1]
                raise InputError(first_label, f"multi-part message (sequence id {msg.seq_id}) is missing "
                                              f"fragment {len(pending[key][0]) + 1} of {msg.frag_cnt}")
            pending[key] = ([msg], label)
        else:
            if key not in pending:
                raise InputError(label, f"fragment {msg.frag_num} of {msg.frag_cnt} (sequence id "
                                        f"{msg.seq_id}) without its earlier fragments")
            parts, first_label = pending[key]
            if msg.frag_num != len(parts) + 1:
                raise InputError(label, f"fragment {msg.frag_num} of {msg.frag_cnt} out of order "
                                        f"(expected {len(parts) + 1})")
            parts.append(msg)
        parts, first_label = pending[key]
        if len(parts) == msg.frag_cnt:
            try:
                complete.append((NMEAMessage.assemble_from_iterable(parts), first_label))
            except _PYAIS_ERRORS as err:
                raise InputError(first_label, f"cannot assemble multi-part message: {err}") from None
            del pending[key]
    for (seq_id, _channel, count), (parts, first_label) in pending.items():
        raise InputError(first_label, f"multi-part message (sequence id {seq_id}) is missing fragment "
                                      f"{len(parts) + 1} of {count}")
    return complete


def _decode(msg: NMEAMessage, label: str) -> dict | None:
    """Decoded fields of a message we use, or None for other message types."""
    try:
        msg_type = msg.ais_id
    except _PYAIS_ERRORS as err:
        raise InputError(label, f"cannot read the message type: {type(err).__name__}") from None
    if msg_type not in (1, 2, 3, 5, 18, 24):
        return None
    try:
        fields: dict[str, Any] = msg.decode().asdict()
    except _PYAIS_ERRORS as err:
        raise InputError(label, f"cannot decode message type {msg_type}: {type(err).__name__}: {err}") from None
    key = (24, fields.get("partno")) if msg_type == 24 else msg_type
    if key not in MIN_PAYLOAD_BITS:
        raise InputError(label, f"message type 24 with unknown part number {fields.get('partno')}")
    bits = len(msg.payload) * 6 - int(msg.fill_bits or 0)
    if bits < MIN_PAYLOAD_BITS[key]:
        raise InputError(label, f"truncated payload: message type {msg_type} has {bits} bits, "
                                f"needs at least {MIN_PAYLOAD_BITS[key]}")
    return fields


def decode_ais(sentences: Sequence[str], source: str = "AIS", labels: Sequence[str] | None = None) -> AisReport:
    """Decode ``sentences`` into one :class:`AisReport`. Blank lines and lines starting with '#' are skipped.

    labels: one name per sentence for error messages (default "<source> sentence <i>").
    """
    kept = _kept_lines(sentences, source, labels)
    static, positions = _by_ship(_assemble([s for s, _ in kept], [lab for _, lab in kept]))
    with_dims = [m for m, e in static.items() if "length" in e]
    if not with_dims:
        raise InputError(source, "no static data: need message type 5 (class A) or type 24 part B (class B) "
                                 "for the ship's dimensions")
    if len(with_dims) > 1:
        raise InputError(source, f"static data of several ships (MMSI {', '.join(map(str, sorted(with_dims)))}): "
                                 "give the sentences of one ship")
    mmsi = with_dims[0]
    report = _static_report(mmsi, static[mmsi])
    if (pos := positions.get(mmsi)) is not None:
        _add_position(report, pos)
    return report


def _kept_lines(sentences: Sequence[str], source: str, labels: Sequence[str] | None) -> list[tuple[str, str]]:
    """(sentence, label) of every line that is not blank or a '#' comment; anything that is not text, or no
    line at all, is an :class:`InputError`."""
    if isinstance(sentences, (str, bytes)) or not isinstance(sentences, Sequence):
        raise InputError(source, "AIS data must be a list of NMEA sentences")
    labels = list(labels) if labels is not None else [f"{source} sentence {i + 1}" for i in range(len(sentences))]
    kept = [(s.strip(), lab) for s, lab in zip(sentences, labels, strict=True)
            if not isinstance(s, str) or (s.strip() and not s.strip().startswith("#"))]
    for s, lab in kept:
        if not isinstance(s, str):
            raise InputError(lab, f"expected a text line, got {type(s).__name__}")
    if not kept:
        raise InputError(source, "no AIS sentences given")
    return kept


def _by_ship(messages: list[tuple[NMEAMessage, str]]) -> tuple[dict[int, dict], dict[int, dict]]:
    """Per MMSI: the static data (type 5, type 24 parts A and B, with the labels they came from) and the last
    position report."""
    static: dict[int, dict] = {}
    positions: dict[int, dict] = {}
    for msg, label in messages:
        fields = _decode(msg, label)
        if fields is None:
            continue
        mmsi = int(fields["mmsi"])
        kind = fields["msg_type"]
        if kind in POSITION_TYPES:
            positions[mmsi] = fields
        elif kind == 5 or (kind == 24 and fields["partno"] == 1):
            entry = static.setdefault(mmsi, {"labels": []})
            entry["labels"].append(label)
            entry["ship_type"] = int(fields["ship_type"])
            entry["length"] = int(fields["to_bow"]) + int(fields["to_stern"])
            entry["breadth"] = int(fields["to_port"]) + int(fields["to_starboard"])
            if kind == 5:
                entry["draught"] = float(fields["draught"])
                entry["name"] = (fields.get("shipname") or "").strip()
        elif kind == 24:  # part A: the name
            static.setdefault(mmsi, {"labels": []}).setdefault("name", (fields.get("shipname") or "").strip())
    return static, positions


def _static_report(mmsi: int, entry: dict) -> AisReport:
    """The report of one ship's static data (its dimensions must be given: 0 = not available)."""
    if entry["length"] <= 0 or entry["breadth"] <= 0:
        raise InputError(entry["labels"][-1], f"static data of MMSI {mmsi} has no dimensions (length "
                                              f"{entry['length']} m, breadth {entry['breadth']} m; 0 = not "
                                              "available)")
    report = AisReport()
    report.mmsi = mmsi
    report.name = entry.get("name", "")
    report.ship_type_code = entry["ship_type"] or None
    report.length_m = float(entry["length"])
    report.breadth_m = float(entry["breadth"])
    report.draught_m = entry.get("draught") or None  # 0 = not available
    report.static_from = list(entry["labels"])
    return report


def _add_position(report: AisReport, pos: dict) -> None:
    """Position and heading of a position report, where available (lat 91 / lon 181, heading 511 and course 360
    mean not available; the course stands in for a missing heading)."""
    lat, lon = pos.get("lat"), pos.get("lon")
    if lat is not None and lon is not None and abs(lat) <= 90 and abs(lon) <= 180:
        report.lat_deg, report.lon_deg = float(lat), float(lon)
    heading = pos.get("heading")
    course = pos.get("course")
    if heading is not None and int(heading) != HEADING_NOT_AVAILABLE and 0 <= heading < 360:
        report.heading_deg = float(heading)
    elif course is not None and 0 <= course < 360:
        report.heading_deg = float(course)


def particulars_from_report(report: AisReport, overrides: Mapping[str, float] | None = None,
                            ship_type: ShipType | None = None, source: str = "AIS"
                            ) -> tuple[ShipParticulars, dict[str, str]]:
    """Particulars from a decoded report; ``overrides`` (config values) win over AIS values."""
    known: dict[str, float] = {}
    given_by: dict[str, str] = {}
    for key, value in (("length_bp_m", report.length_m), ("breadth_m", report.breadth_m),
                       ("draft_m", report.draught_m), ("lat_deg", report.lat_deg),
                       ("lon_deg", report.lon_deg), ("heading_deg", report.heading_deg)):
        if value is not None:
            known[key], given_by[key] = float(value), "ais"
    for key, value in (overrides or {}).items():
        if key not in DIMENSION_FIELDS + POSITION_FIELDS:
            raise InputError(source, f"unknown particulars override {key!r}")
        if value is not None:
            known[key], given_by[key] = float(value), "config"
    resolved_type = ship_type
    if resolved_type is not None:
        given_by["ship_type"] = "config"
    else:
        resolved_type = ship_type_from_ais_code(report.ship_type_code)
        if resolved_type is not None:
            given_by["ship_type"] = "ais"
        else:
            resolved_type = ShipType.STYLIZED  # AIS type code without a family of ours: documented fallback
    particulars, provenance = complete_particulars(resolved_type, known, source, given_by,
                                                   name=report.name, mmsi=report.mmsi)
    provenance["ship_type"] = given_by.get(
        "ship_type", f"default (AIS type code {report.ship_type_code} has no family)")
    return particulars, provenance


def particulars_from_ais(sentences: Sequence[str], overrides: Mapping[str, float] | None = None, *,
                         ship_type: ShipType | None = None, source: str = "AIS",
                         labels: Sequence[str] | None = None) -> ShipParticulars:
    """Ship particulars from AIS NMEA sentences.

    sentences: NMEA lines ("!AIVDM,..." / "!AIVDO,..."), multi-part messages in order;
    overrides: config values (metres / degrees) that replace AIS values or the derived ones;
    ship_type: forces the family (else mapped from the AIS type code, see ``ship_type_from_ais_code``).
    Depth and superstructure height are derived from per-type ratios unless overridden; the derived field
    names are in ``ShipParticulars.derived``. Raises :class:`InputError` for any bad sentence.
    """
    report = decode_ais(sentences, source, labels)
    return particulars_from_report(report, overrides, ship_type, source)[0]
