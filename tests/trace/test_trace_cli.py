"""`stvm trace`: record, compare (exit 4 with the first divergence), usage errors (exit 2)."""

from __future__ import annotations

from pathlib import Path

from stvm.cli import main

ST = Path(__file__).parent / "st"
COUNTER = str(ST / "counter.st")


def test_record_every_format(tmp_path, capsys):
    outs = [str(tmp_path / f"t{suffix}") for suffix in (".jsonl", ".csv", ".vcd", ".json")]
    args = ["trace", COUNTER, "--cycles", "10", "--watch", "Main.counter", "Main.flag"]
    for out in outs:
        args += ["-o", out]
    assert main(args) == 0
    assert all(Path(out).stat().st_size > 0 for out in outs)
    assert "wrote" in capsys.readouterr().err


def test_compare_equal_and_different(tmp_path, capsys):
    golden = str(tmp_path / "g.jsonl")
    assert main(["trace", COUNTER, "--cycles", "10", "--watch", "Main.*", "-o", golden]) == 0
    assert main(["trace", COUNTER, "--cycles", "10", "--watch", "Main.*", "--compare", golden]) == 0
    assert "trace matches" in capsys.readouterr().err
    mutated = tmp_path / "counter.st"
    mutated.write_text(Path(COUNTER).read_text().replace("limit : INT := 5;", "limit : INT := 6;"))
    code = main(["trace", str(mutated), "--cycles", "10", "--watch", "Main.*", "--compare", golden, "--context", "2"])
    err = capsys.readouterr().err
    assert code == 4
    assert "first divergence at scan 0 (t=T#0s)" in err
    assert "variable: Main.limit" in err and "expected: 5" in err and "actual:   6" in err


def test_writer_named_in_the_report(tmp_path, capsys):
    golden = str(tmp_path / "g.jsonl")
    assert main(["trace", COUNTER, "--cycles", "10", "--watch", "Main.flag", "-o", golden]) == 0
    mutated = tmp_path / "counter.st"
    mutated.write_text(Path(COUNTER).read_text().replace("IF counter > limit THEN", "IF counter > limit + 1 THEN"))
    assert main(["trace", str(mutated), "--cycles", "10", "--watch", "Main.flag", "--compare", golden]) == 4
    err = capsys.readouterr().err
    assert "first divergence at scan 5 (t=T#5ms)" in err and "expected: TRUE" in err
    # the actual value (FALSE) was never written: it is the initial value
    assert "last written: initial value" in err


def test_usage_errors(tmp_path, capsys):
    assert main(["trace", COUNTER, "--watch", "Main.*"]) == 2                       # no -o / --compare
    assert main(["trace", COUNTER, "--watch", "Main.*", "-o", str(tmp_path / "x.txt")]) == 2
    assert main(["trace", COUNTER, "--watch", "Nope.*", "-o", str(tmp_path / "x.csv")]) == 2
    assert main(["trace", COUNTER, "-o", str(tmp_path / "x.csv")]) == 2              # nothing to watch
    assert main(["trace", COUNTER, "--watch", "Main.*", "--compare", str(tmp_path / "none.jsonl")]) == 2
    assert main(["trace", "missing.st", "--watch", "Main.*", "-o", str(tmp_path / "x.csv")]) == 2
    assert main(["trace", COUNTER, "--watch", "Main.*", "--fault", "bogus", "-o", str(tmp_path / "x.csv")]) == 2
    assert main(["trace", COUNTER, "--watch", "Main.*", "--svg", "-o", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err
    assert "matches no variable" in err and "nothing to record" in err


def test_compile_error_and_runtime_fault(tmp_path, capsys):
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM Main\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n")
    assert main(["trace", str(bad), "--watch", "Main.x", "-o", str(tmp_path / "x.csv")]) == 1
    div = tmp_path / "div.st"
    div.write_text("PROGRAM Main\nVAR d : INT := 2; END_VAR\nd := d - 1;\nd := 10 / d;\nEND_PROGRAM\n")
    assert main(["trace", str(div), "--watch", "Main.d", "--cycles", "5", "-o", str(tmp_path / "d.jsonl")]) == 3
    assert "division" in capsys.readouterr().err
    assert "runtime fault" in (tmp_path / "d.jsonl").read_text()
