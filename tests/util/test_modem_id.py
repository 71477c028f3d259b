import logging

from pygoby.util.modem_id import ModemIdLookup


def test_parse_lookup_file(tmp_path, caplog):
    path = tmp_path / "lookup.txt"
    path.write_text(
        "// modem id, vehicle name, vehicle type\n"
        "0, broadcast, broadcast\n"
        "1,\tendeavor ,ship  // the ship\n"
        "3, unicorn, auv, dock # comment\n"
        "\n"
        "bad line\n"
    )
    with caplog.at_level(logging.WARNING):
        lookup = ModemIdLookup.from_file(path)
    assert len(lookup) == 3
    assert lookup.name(1) == "endeavor"
    assert lookup.type(1) == "ship"
    assert lookup.location(3) == "dock"
    assert lookup.location(0) == "broadcast"
    assert lookup.name(9) == "9"
    assert lookup.type(9) == "unknown_type"
    assert lookup.modem_id("UNICORN") == 3
    assert lookup.modem_id("nobody") == 0
    assert "line 6 is invalid" in caplog.text


def test_unreadable_file_gives_empty_table(tmp_path, caplog):
    with caplog.at_level(logging.WARNING):
        lookup = ModemIdLookup.from_file(tmp_path / "missing.txt")
    assert len(lookup) == 0
    assert "cannot read modem id lookup file" in caplog.text
