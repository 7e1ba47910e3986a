"""``drape simulate`` input errors: one line, exit status 2, before any simulation."""

from datagen.cli import main


def test_simulate_rejects_bad_output_and_unknown_garment(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path / "run.txt")]) == 2
    assert "--out must end in .npz" in capsys.readouterr().err
    assert main(["simulate", "--out", str(tmp_path / "missing" / "run.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["simulate", "--frames", "0", "--out", str(tmp_path / "run.npz")]) == 2
    assert "--frames must be >= 1" in capsys.readouterr().err
