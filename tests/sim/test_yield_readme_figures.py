"""``python -m benchmarks readme-figures`` (issue 66): README's figures found, the commands' outputs read,
and a figure that moved flagged. The outputs are the real ones the project keeps under docs/bench/."""

from pathlib import Path

import pytest

from benchmarks import readme_figures as R

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "docs" / "bench"


def test_every_figure_record_finds_its_value_in_the_readme():
    text = (ROOT / "README.md").read_text()
    missing = [f.name for f in R.FIGURES if R.readme_values(text, f) is None]
    assert not missing, f"README no longer quotes these as their records expect: {missing}"
    assert len({f.name for f in R.FIGURES}) == len(R.FIGURES)
    for f in R.FIGURES:
        assert f.device in ("cpu", "cuda")
        assert (f.parse is None) == (not f.command), f.name
        assert f.command or f.needs, f.name


def test_a_readme_figure_is_found_across_line_breaks_and_in_words():
    fig = next(f for f in R.FIGURES if f.name == "tiny-generate")
    text = ("(the `tiny` dataset preset: six scenes\nsimulated on the CPU into a validated zarr store, "
            "`tiny.zarr`; about 10 minutes on 2 cores). It")
    assert R.readme_values(text, fig) == ("six", "10")
    assert R.number("six") == 6 and R.number("53,520") == 53520 and R.number("0.82") == 0.82


def test_the_outputs_of_the_commands_are_read():
    small = (BENCH / "issues_59_61_66_h200" / "generate.txt").read_text().split("## pattern garments")[0]
    assert R.parse_generate(small, 71.0) == (56, 56)
    pm = (BENCH / "paper_motion_one_gpu" / "generate_pm_h200.log").read_text()
    assert R.parse_paper_motion(pm, 566.59) == (9, 26.6, 252, 53520, 223)
    assert R.parse_cusick((BENCH / "sim_physics_limits_cpu" / "cusick.txt").read_text().split("\n# ")[0], 0.0) == (6, 6)
    assert R.parse_strips((BENCH / "sim_h200" / "physics_tests_cpu.txt").read_text(), 0.0) == (0.87,)
    six = (BENCH / "issues_59_61_66_h200" / "six.txt").read_text().split("\n# the previous session")[0]
    assert R.parse_six(six, 0.0) == (6,)
    assert R.parse_throughput((BENCH / "sim_h200" / "throughput.txt").read_text(), 0.0) == (223.2,)
    newton = (BENCH / "issues_59_61_66_h200" / "newton.txt").read_text().split("## before")[0]
    on64, on256, off64, off256 = R.parse_newton(newton, 0.0)
    assert (round(on64, 2), round(on256, 2), round(off64, 2), round(off256, 2)) == (1.13, 1.37, 0.82, 0.91)
    export = ("file                    write s       MB  frames/s  validate s  errors  read-back\n"
              "anim.usd                   2.40    216.3     124.8        0.01       0  exact\n"
              "anim.usda                 14.56    684.8      20.6       14.21       0  exact\n")
    assert R.parse_export(export, 0.0) == (2.4, 216.3)
    assert R.parse_contracts("Contracts: 20 kept, 0 broken.\n", 0.0) == (20,)
    info = ("               preset thin: height 1.70 m, mass 53.5 kg, BMI 18.5\n"
            "            preset regular: height 1.70 m, mass 65.3 kg, BMI 22.6\n"
            "                preset fat: height 1.70 m, mass 89.6 kg, BMI 31.0\n")
    assert R.parse_bmi(info, 0.0) == (18.5, 22.6, 31.0)
    with pytest.raises(ValueError):
        R.parse_generate("Traceback (most recent call last):\n", 1.0)


def test_a_figure_that_moved_is_flagged_and_one_within_its_tolerance_is_not():
    fig = next(f for f in R.FIGURES if f.name == "small")
    assert R.row(fig, ("52", "56"), (52.0, 56.0), "").verdict == "ok"
    assert R.row(fig, ("52", "56"), (55.0, 56.0), "").verdict == "DIFFERS"
    assert R.row(fig, None, (55.0, 56.0), "").verdict.startswith("README NO LONGER")
    assert R.row(fig, ("52", "56"), None, "exit status 1").verdict == "exit status 1"
    build = next(f for f in R.FIGURES if f.name == "body-build")  # "about 15 s": half either way
    assert R.compare(("15",), (21.0,), build.tolerance) and not R.compare(("15",), (23.0,), build.tolerance)
    table = R.format_table([R.row(fig, ("52", "56"), (55.0, 56.0), "")]).splitlines()
    assert table[0].split()[:2] == ["figure", "README"] and "DIFFERS" in table[1] and fig.command in table[1]
