"""``lsdae fix`` (conformance/commands/fix.py) in this process: its diff, the lines it prints,
which rules it fixes and its exit code."""
from __future__ import annotations

from pathlib import Path

import pytest

from conformance.fixes.fixers import UNSAFE_FIXERS
from tests.clikit import lsdae
from tests.fixtures import DEFECTS, all_cases, build_defect, materialise

MANIFEST = "extra/org.fmi-standard.fmi-ls-dae/fmi-ls-manifest.xml"
# DAE104/fail-1: the manifest's description lacks its final full stop (a safe fix)
DESCRIPTION_DIFF = f"""\
--- a/{MANIFEST}
+++ b/{MANIFEST}
@@ -2,7 +2,7 @@
 <fmiDAEManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
   fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-dae"
   fmi-ls:fmi-ls-version="1.0.0-alpha.1"
-  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI">
+  fmi-ls:fmi-ls-description="Layered standard for DAE support in FMI.">
   <EnableDAEParameter valueReference="1"/>
   <AlgebraicVariables>
     <AlgebraicVariable valueReference="4"/>
"""
NO_FIX_FOR_DAE401 = ("no fix for DAE401 residual-unknown-vr: which variable holds the residual "
                     "is known only to the model's author; lsdae does not guess a value "
                     "reference\n")


def _case(case_id: str, dest: Path) -> Path:
    return materialise(next(c for c in all_cases() if c.id == case_id), dest)


def test_diff_is_the_whole_stdout_and_the_summary_goes_to_stderr(tmp_path):
    source = _case("DAE104/fail-1", tmp_path)
    assert lsdae("fix", str(source), "--diff", "--no-probes") == (
        0, DESCRIPTION_DIFF, "fixed 1 finding, 0 remain\n")


def test_what_remains_is_printed_with_why_no_fix_exists(tmp_path):
    """DAE010/fail-2: the missing namespace prefix is fixed, the residual's unknown value
    reference is not (no fix can invent it): exit 1."""
    source = _case("DAE010/fail-2", tmp_path / "in")
    out = tmp_path / "out"
    code, printed, err = lsdae("fix", str(source), "-o", str(out), "--no-probes",
                               "--color", "never")
    assert (code, err) == (1, "")
    assert printed.startswith("error[DAE401 residual-unknown-vr]: ")
    assert printed.endswith(f"\n{NO_FIX_FOR_DAE401}fixed 1 finding, 1 remains\n")
    assert (out / MANIFEST).is_file()


def test_ignore_leaves_its_rules_unfixed(tmp_path):
    source = _case("DAE104/fail-1", tmp_path / "in")
    out = tmp_path / "out"
    assert lsdae("fix", str(source), "-o", str(out), "--no-probes", "--ignore", "DAE104") == (
        0, "fixed 0 findings, 0 remain\n", "")
    assert (out / MANIFEST).read_bytes() == (source / MANIFEST).read_bytes()


def test_several_fmus_name_themselves_in_the_summary(tmp_path):
    first = _case("DAE104/fail-1", tmp_path / "a")
    second = _case("DAE010/fail-2", tmp_path / "b")
    code, out, err = lsdae("fix", str(first), str(second), "--diff", "--no-probes",
                           "--color", "never")
    assert code == 1
    assert out.startswith(DESCRIPTION_DIFF + f"--- a/{MANIFEST}\n+++ b/{MANIFEST}\n")
    assert err.startswith(f"fixed 1 finding, 0 remain ({first})\nerror[DAE401 ")
    assert err.endswith(f"\n{NO_FIX_FOR_DAE401}fixed 1 finding, 1 remains ({second})\n")


def test_output_for_several_fmus_is_a_usage_error(tmp_path):
    first = _case("DAE104/fail-1", tmp_path / "a")
    second = _case("DAE010/fail-2", tmp_path / "b")
    assert lsdae("fix", str(first), str(second), "-o", str(tmp_path / "out")) == (
        2, "", "lsdae: -o takes one FMU; fix several with --in-place or --diff\n")


def test_select_keeps_other_rules_out_of_the_first_check(tmp_path):
    """--select DAE103 on an FMU whose only fault is DAE104's: nothing is fixed."""
    source = _case("DAE104/fail-1", tmp_path / "in")
    assert lsdae("fix", str(source), "--diff", "--no-probes", "--select", "DAE103") == (
        0, "", "fixed 0 findings, 0 remain\n")


@pytest.mark.parametrize("defect", [
    next(d for d in DEFECTS if d.code in {c for codes, _ in UNSAFE_FIXERS.values()
                                          for c in codes} and not d.defines)],
    ids=lambda d: d.id)
def test_unsafe_fixes_from_the_probes(defect):
    """The probes observe a dependency the manifest does not declare; --unsafe-fixes adds it."""
    source = build_defect(defect)
    code, out, err = lsdae("fix", str(source), "--diff", "--color", "never")
    assert (code, out) == (1, "") and err.endswith("fixed 0 findings, 1 remains\n")
    code, out, err = lsdae("fix", str(source), "--diff", "--unsafe-fixes", "--color", "never")
    assert (code, err) == (0, "fixed 1 finding, 0 remain\n")
    assert out.startswith(f"--- a/{MANIFEST}\n+++ b/{MANIFEST}\n")
    added = [line for line in out.splitlines() if line.startswith("+")]
    assert len(added) == 2   # the +++ header and the one widened line
