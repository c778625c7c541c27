"""The audit's verdicts come from the derivation, not from constants."""
import json

import pytest

from derivations import audit, printed
from nonholo.cli.entry import main


@pytest.fixture(scope="module")
def audit_json():
    import contextlib
    import io
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["audit", "--json"]) == 0
    return json.loads(buf.getvalue())


@pytest.mark.slow
def test_json_shape(audit_json):
    assert len(audit_json) == len(audit.CHECKS)
    for item in audit_json:
        assert set(item) == {"equation", "verdict", "note"}


@pytest.mark.slow
def test_expected_verdicts(audit_json):
    verdicts = {item["equation"]: item["verdict"] for item in audit_json}
    assert verdicts.pop("(12)") == audit.TYPO
    assert verdicts.pop("(7): P(θ)") == audit.MISLABELED
    assert set(verdicts.values()) == {audit.VERIFIED}


@pytest.mark.slow
def test_eq12_note_names_the_repair(audit_json):
    note = next(i["note"] for i in audit_json if i["equation"] == "(12)")
    assert "row 1 holds as printed" in note
    assert note.count("spurious") == 2


def test_wrong_transcription_is_caught(monkeypatch):
    monkeypatch.setitem(printed.DELTA, "python", "r12*r31 - r21*r32")
    assert audit.check_delta().verdict == audit.WRONG
    monkeypatch.setitem(printed.DELTA_CUBIC, "python", "xi**3*(sin(phi) - cos(phi))/(1 - zeta**2) + xi*eta + eta*zeta")
    assert audit.check_delta_cubic().verdict == audit.WRONG


@pytest.mark.slow
def test_unrepairable_row_is_wrong(monkeypatch):
    rows = list(printed.EQ_12["rows"])
    rows[2] = rows[2].replace("-r32", "+r32")
    monkeypatch.setitem(printed.EQ_12, "rows", tuple(rows))
    assert audit.check_eq_12().verdict == audit.WRONG


def test_label_exp_would_be_verified_if_rhs_were_exp(monkeypatch):
    monkeypatch.setitem(printed.P_AFTER_7, "rhs_coefficients", ("sin(alpha)/alpha", "(1 - cos(alpha))/alpha**2"))
    assert audit.check_P().verdict == audit.VERIFIED
