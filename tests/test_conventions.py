"""Controller and file conventions (issue 16, point 5): axis words without a decimal point, UTF-8 byte-order
marks, duplicate ball-bar runs, absurd numbers in a candidates file."""

from __future__ import annotations

import codecs

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import InputError, ParameterError, load_campaign, units
from mtmcal_bayes.datasets import builtin_campaign_text, builtin_text, data_path
from mtmcal_bayes.io.campaign_reader import load_truth
from mtmcal_bayes.io.dprnt import read_dprnt
from mtmcal_bayes.io.gcode import parse_program, read_program, rewrite
from mtmcal_bayes.planning.candidates import MAX_LENGTH_MM, MAX_REPEATS, read_candidates

from .conftest import DATA
from .test_bad_inputs import assert_one_line_error, good_trace

BOM = codecs.BOM_UTF8.decode("utf-8")


# --------------------------------------------------------------------------- axis words without a decimal point
#: three blocks of the B-axis X-direction pattern (Fig 4.30(a), to 1 µm / 0.001°) in three spellings
DECIMAL_PROGRAM = ("%\nO1000 (BX)\nG90 G21\n"
                   "G01 X-390.000 Y0.000 Z-112.261 B0.000 C0.000 F2000\n"
                   "G01 X-388.272 Y0.000 Z-112.265 B0.278 C0.000 F2000\n"
                   "G01 X-386.544 Y0.000 Z-112.277 B0.556 C0.000 F2000\nM30\n%\n")
MICRON_PROGRAM = ("%\nO1000 (BX)\nG90 G21\n"
                  "G01 X-390000 Y0 Z-112261 B0 C0 F2000\n"
                  "G01 X-388272 Y0 Z-112265 B278 C0 F2000\n"
                  "G01 X-386544 Y0 Z-112277 B556 C0 F2000\nM30\n%\n")
WHOLE_DECIMAL = ("G90 G21\nG01 X-390. Y0. Z-112. B0. C0. F2000\nG01 X-380. Y0. Z-113. B1. C0.\nM30\n")
WHOLE_INTEGER = ("G90 G21\nG01 X-390 Y0 Z-112 B0 C0 F2000\nG01 X-380 Y0 Z-113 B1 C0\nM30\n")


def test_integer_axis_word_is_refused_with_one_line(run_cli, tmp_path):
    prog = tmp_path / "prog.nc"
    prog.write_text(DECIMAL_PROGRAM.replace("X-388.272", "X100"))
    line = assert_one_line_error(run_cli, ["compensate", prog, "-o", tmp_path / "out.nc"], tmp_path, prog,
                                 "line 5", "X100 has no decimal point")
    assert ("many controls read it as 100 least-input increments (0.1 mm at 1 µm), not 100 mm; write X100. "
            "or give the control's integer unit (um or mm)") in line
    assert not (tmp_path / "out.nc").exists()


@pytest.mark.parametrize("word", ["B90", "C-45", "Z-5", "Y+7"])
def test_every_axis_word_follows_the_rule(word):
    text = f"G01 X-390.000 Y0.000 Z-112.261 B0.000 C0.000\nG01 {word}\n"
    with pytest.raises(InputError) as info:
        parse_program(text, "p.nc")
    assert info.value.key == "line 2" and info.value.message.startswith(f"{word} has no decimal point")


def test_words_that_are_not_positions_and_zeros_are_not_affected():
    """Zeros read the same either way; G/M/N/F/S/T/H words, a G04 dwell, G10.9 and G28 axes are no positions."""
    text = ("N10 G90 G21 G17\nT23 M06\nG10.9 X0\nG28 X0 Y0 Z0\nM03 S1000\nG43 H1 G00 X-390. Y0 Z-112.26 B0 C0\n"
            "G04 X2\nN20 G01 X-388.272 Y0 Z-112.265 B0.278 C-0 F2000\nM30\n")
    prog = parse_program(text, "p.nc")
    np.testing.assert_array_equal(prog.positions(), [[-390.0, 0, -112.26, 0, 0], [-388.272, 0, -112.265, 0.278, 0]])


@pytest.mark.parametrize("unit, integer, decimal", [("um", MICRON_PROGRAM, DECIMAL_PROGRAM),
                                                    ("mm", WHOLE_INTEGER, WHOLE_DECIMAL)], ids=["um", "mm"])
def test_integer_unit_gives_the_positions_of_the_decimal_program(run_cli, tmp_path, unit, integer, decimal):
    """--integer-unit um reads X-388272 as -388.272 mm and B278 as 0.278°, mm as whole mm and degrees: the
    positions, and the compensated positions, are those of the program written with decimal points."""
    (tmp_path / "int.nc").write_text(integer)
    (tmp_path / "dec.nc").write_text(decimal)
    assert read_program(tmp_path / "int.nc", integer_unit=unit).positions().tolist() == \
        read_program(tmp_path / "dec.nc").positions().tolist()
    code, _, err = run_cli("compensate", tmp_path / "int.nc", "-o", tmp_path / "int_out.nc", "--integer-unit", unit)
    assert code == 0, err
    code, _, err = run_cli("compensate", tmp_path / "dec.nc", "-o", tmp_path / "dec_out.nc")
    assert code == 0, err
    out_int = read_program(tmp_path / "int_out.nc", integer_unit=unit)
    out_dec = read_program(tmp_path / "dec_out.nc")
    np.testing.assert_array_equal(out_int.positions(), out_dec.positions())
    assert not np.array_equal(out_dec.positions(), read_program(tmp_path / "dec.nc").positions())  # corrected
    for block in out_int.motion:  # a corrected X/Z is written in mm with a decimal point, B and C as written
        for w in block.words:
            text = block.text[w.start:w.end]
            if w.letter in "XZ":
                assert "." in text, block.text
    assert [b.text.split()[4] for b in out_int.motion] == [b.text.split()[4] for b in
                                                           parse_program(integer, "i", integer_unit=unit).motion]


def test_rewrite_keeps_an_unchanged_integer_word_and_writes_a_changed_one_in_mm():
    prog = parse_program("G01 X100 Y-2500 Z0 B90 C0\n", "p.nc", integer_unit="um")
    assert prog.positions().tolist() == [[0.1, -2.5, 0.0, 0.09, 0.0]]
    assert rewrite(prog, [[0.1, -2.5, 0.0]]) == "G01 X100 Y-2500 Z0 B90 C0\n"
    assert rewrite(prog, [[0.1012, -2.5, 0.0]]) == "G01 X0.101 Y-2500 Z0 B90 C0\n"  # 1 µm, the increment's
    prog = parse_program("G01 X100 Y-2500 Z0\n", "p.nc", integer_unit="mm")
    assert rewrite(prog, [[100.0012, -2500.0, 0.0]]) == "G01 X100.001 Y-2500 Z0\n"


def test_integer_unit_must_be_known():
    with pytest.raises(ParameterError, match="integer_unit"):
        parse_program(DECIMAL_PROGRAM, "p.nc", integer_unit="inch")
    with pytest.raises(ParameterError, match="integer_unit"):
        mb.compensate(data_path("fig4_30a_bx_original.nc"), integer_unit="0.1um")


def test_thesis_program_needs_no_integer_unit():
    """Fig 4.30(a) writes every axis word with a decimal point: read as before, whatever integer_unit says."""
    plain = read_program(data_path("fig4_30a_bx_original.nc")).positions()
    assert plain.shape == (10, 5)
    for unit in ("um", "mm"):
        np.testing.assert_array_equal(read_program(data_path("fig4_30a_bx_original.nc"), integer_unit=unit)
                                      .positions(), plain)


# --------------------------------------------------------------------------- UTF-8 byte-order mark
def _with_bom(path, text: str):
    path.write_bytes(codecs.BOM_UTF8 + text.encode("utf-8"))
    return path


def test_campaign_with_bom_loads_identically(tmp_path):
    text, _ = builtin_campaign_text()
    (tmp_path / "plain").mkdir()
    (tmp_path / "bom").mkdir()
    plain = tmp_path / "plain" / "c.toml"
    plain.write_text(text, encoding="utf-8")
    bom = _with_bom(tmp_path / "bom" / "c.toml", text)
    assert bom.read_bytes().startswith(codecs.BOM_UTF8)
    mb.save_campaign(load_campaign(plain), tmp_path / "plain.toml")
    mb.save_campaign(load_campaign(bom), tmp_path / "bom.toml")
    assert (tmp_path / "bom.toml").read_text() == (tmp_path / "plain.toml").read_text()
    a, b = mb.identify(plain).to_json(), mb.identify(bom).to_json()
    a.pop("campaign"), b.pop("campaign")
    assert a == b


def test_nc_program_and_dprnt_with_bom_read_the_same(tmp_path):
    nc = builtin_text("fig4_30a_bx_original.nc")
    np.testing.assert_array_equal(read_program(_with_bom(tmp_path / "p.nc", nc)).positions(),
                                  read_program(data_path("fig4_30a_bx_original.nc")).positions())
    dp = builtin_text("fig5_13_dprnt_output.txt")
    np.testing.assert_array_equal(read_dprnt(_with_bom(tmp_path / "d.txt", dp)).xyz,
                                  read_dprnt(data_path("fig5_13_dprnt_output.txt")).xyz)


def test_trace_candidates_and_truth_with_bom(tmp_path, thesis):
    base = (DATA / "minimal_one_repeat.toml").read_text()
    head, _ = base.split("[[ballbar.runs]]", 1)
    _with_bom(tmp_path / "cr.csv", good_trace("CR"))
    _with_bom(tmp_path / "c.toml", head + '[[ballbar.runs]]\npattern = "CR"\nsetup = "RB1"\nmount = "C"\n'
              'trace_csv = "cr.csv"\n')
    run = load_campaign(tmp_path / "c.toml").ballbar.runs[0]
    assert units.from_internal(run.repeats["ex"], "um") == pytest.approx([-47.9], abs=1e-3)
    cands = _with_bom(tmp_path / "cands.toml", '[[candidate]]\npattern = "CR"\nsetup = "RB2"\nmount = "C"\n')
    assert [c.setup.id for c in read_candidates(cands, thesis)] == ["RB2"]
    truth = _with_bom(tmp_path / "truth.toml", "[deviations]\nbeta_XB_arcsec = -24.11\n")
    assert load_truth(truth, thesis).deviations["beta_XB"] == pytest.approx(units.to_internal(-24.11, "arcsec"))


def test_a_bom_elsewhere_or_utf16_is_still_an_error(tmp_path):
    bad = tmp_path / "p.nc"
    bad.write_bytes(codecs.BOM_UTF16_LE + "G01 X1. Y2. Z3.\n".encode("utf-16-le"))
    with pytest.raises(InputError, match="not UTF-8 text"):
        read_program(bad)
    bad.write_text("G01 X1. Y2. Z3.\n" + BOM + "G01 X2. Y2. Z3.\n", encoding="utf-8")
    with pytest.raises(InputError, match="line 2"):
        read_program(bad)


# --------------------------------------------------------------------------- duplicate ball-bar runs
MINIMAL = (DATA / "minimal_one_repeat.toml").read_text()
CR_AGAIN = '\n[[ballbar.runs]]\npattern = "CR"\nsetup = "RB1"\nmount = "{mount}"\nex_um = [-48.2]\ney_um = [25.9]\n'


def test_duplicate_run_is_refused_naming_the_earlier_run(tmp_path):
    path = tmp_path / "dup.toml"
    path.write_text(MINIMAL + CR_AGAIN.format(mount="C"))
    with pytest.raises(InputError) as info:
        load_campaign(path)
    err = info.value
    assert err.source == str(path) and err.key == "ballbar.runs[5]"
    assert err.message.startswith("repeats ballbar.runs[2] (pattern CR, setup 'RB1', mount 'C')")
    assert "ex_um = [..., ...]" in err.message and "[ballbar.mounts.<id>]" in err.message


def test_a_re_clamped_ball_with_its_own_mount_is_accepted(tmp_path):
    """The fix the message suggests: the second session's W ball as its own placement (same geometry)."""
    path = tmp_path / "remount.toml"
    path.write_text(MINIMAL.replace("[[ballbar.runs]]", "[ballbar.mounts.C2]\nZ_C_mm = 65.5348\nR_C_mm = 50.0\n\n"
                                    "[[ballbar.runs]]", 1) + CR_AGAIN.format(mount="C2"))
    c = load_campaign(path)
    assert [(r.pattern, r.setup, r.mount) for r in c.ballbar.runs][-1] == ("CR", "RB1", "C2")


def test_duplicate_trace_runs_are_refused(tmp_path):
    head, _ = MINIMAL.split("[[ballbar.runs]]", 1)
    for name in ("a.csv", "b.csv"):
        (tmp_path / name).write_text(good_trace("CR"))
    runs = "".join(f'[[ballbar.runs]]\npattern = "CR"\nsetup = "RB1"\nmount = "C"\ntrace_csv = "{n}"\n\n'
                   for n in ("a.csv", "b.csv"))
    (tmp_path / "t.toml").write_text(head + runs)
    with pytest.raises(InputError) as info:
        load_campaign(tmp_path / "t.toml")
    assert info.value.key == "ballbar.runs[1]" and 'trace_csv = ["a.csv", "b.csv"]' in info.value.message
    (tmp_path / "t.toml").write_text(head + runs.replace('trace_csv = "a.csv"\n\n[[ballbar.runs]]\npattern = "CR"\n'
                                                         'setup = "RB1"\nmount = "C"\ntrace_csv = "b.csv"',
                                                         'trace_csv = ["a.csv", "b.csv"]'))
    assert len(load_campaign(tmp_path / "t.toml").ballbar.runs[0].repeats["ex"]) == 2


# --------------------------------------------------------------------------- absurd candidates
CANDIDATE = '[[candidate]]\npattern = "{pattern}"\n{where}\n{extra}\n'
EXISTING = 'setup = "RB2"\nmount = "C"'
NEW_SETUP = 'R_B_mm = {R_B}\nZ_T_mm = {Z_T}\nX_T_mm = 490.0\nmount = "C"'
NEW_MOUNT = 'setup = "RB1"\nZ_C_mm = {Z_C}\nR_C_mm = {R_C}'

ABSURD = [  # (id, pattern, where, extra, key, fragment)
    ("repeats-1e20", "CR", EXISTING, "repeats = 1e20", "repeats", "is more than 10000"),
    ("repeats-huge-integer", "CR", EXISTING, "repeats = 100000000000000000000", "repeats", "is more than 10000"),
    ("repeats-10001", "CR", EXISTING, "repeats = 10001", "repeats", "is more than 10000"),
    ("repeats-zero", "CR", EXISTING, "repeats = 0", "repeats", "must be positive"),
    ("repeats-negative", "CR", EXISTING, "repeats = -3", "repeats", "must be positive"),
    ("repeats-nan", "CR", EXISTING, "repeats = nan", "repeats", "NaN"),
    ("repeats-inf", "CR", EXISTING, "repeats = inf", "repeats", "infinite"),
    ("repeats-fraction", "CR", EXISTING, "repeats = 2.5", "repeats", "whole number"),
    ("length-1e300", "CR", EXISTING, "length_mm = 1e300", "length_mm", "beyond ±10000 mm"),
    ("length-zero", "CR", EXISTING, "length_mm = 0", "length_mm", "must be positive"),
    ("length-minus-inf", "CR", EXISTING, "length_mm = -inf", "length_mm", "infinite"),
    ("R_B-1e300", "CR", NEW_SETUP.format(R_B="1e300", Z_T=0), "", "R_B_mm", "beyond ±10000 mm"),
    ("R_B-negative", "CR", NEW_SETUP.format(R_B=-5, Z_T=0), "", "R_B_mm", "must be positive"),
    ("Z_T-1e20", "CR", NEW_SETUP.format(R_B=400, Z_T="1e20"), "", "Z_T_mm", "beyond ±10000 mm"),
    ("Z_T-nan", "CR", NEW_SETUP.format(R_B=400, Z_T="nan"), "", "Z_T_mm", "NaN"),
    ("Z_C-negative", "CR", NEW_MOUNT.format(Z_C=-1, R_C=50), "", "Z_C_mm", "must not be negative"),
    ("R_C-1e300", "CR", NEW_MOUNT.format(Z_C=65, R_C="1e300"), "", "R_C_mm", "beyond ±10000 mm"),
    ("setup-and-lever-arms", "CR", EXISTING, "R_B_mm = 400", "R_B_mm", "not both"),
    ("mount-and-geometry", "CR", EXISTING, "R_C_mm = 50", "R_C_mm", "not both"),
]


@pytest.mark.parametrize("pattern, where, extra, key, fragment", [a[1:] for a in ABSURD], ids=[a[0] for a in ABSURD])
def test_absurd_candidates_are_one_line_errors(run_cli, tmp_path, pattern, where, extra, key, fragment):
    cands = tmp_path / "cands.toml"
    cands.write_text(CANDIDATE.format(pattern=pattern, where=where, extra=extra))
    assert_one_line_error(run_cli, ["plan", "--candidates", cands, "-o", tmp_path / "out"], tmp_path, cands,
                          f"candidate[0].{key}", fragment)


def test_candidates_at_the_bounds_are_read(tmp_path, thesis):
    cands = tmp_path / "cands.toml"
    cands.write_text(CANDIDATE.format(pattern="CR", where=NEW_SETUP.format(R_B=MAX_LENGTH_MM, Z_T=-MAX_LENGTH_MM),
                                      extra=f"repeats = {MAX_REPEATS}\nlength_mm = {MAX_LENGTH_MM}"))
    (c,) = read_candidates(cands, thesis)
    assert (c.repeats, c.setup.R_B, c.setup.Z_T, c.length) == (MAX_REPEATS, 1e4, -1e4, 1e4)
