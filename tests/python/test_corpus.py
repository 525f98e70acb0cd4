"""`python -m raycast_tools corpus` on a tiny corpus of fixtures whose outside verdicts are
known (fixtures/check/README.md records the Khronos glTF-Validator's; trimesh 5.2.0 refuses
fixtures/bad/ply_truncated.ply with "PLY is unexpected length"):

* one_accessor_two_primitives.gltf: valid (validator: no issues);
* two_accessors_one_view.gltf: MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE;
* clearcoat_normal_without_tangents.gltf: MESH_PRIMITIVE_NO_TANGENT_SPACE;
* cube_binary_le.ply: trimesh reads it, 12 triangles;
* ply_truncated.ply: trimesh refuses it.

The test checks what the report says of each: the reference's verdict, check's beside it,
the summary's counts. Needs the raycast binary, node and tools/npm/node_modules (npm ci).

Run: .venv/bin/python -m pytest tests/python/test_corpus.py
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest
from binary import RAYCAST, ROOT, needs_binary

VALIDATOR = ROOT / "tools" / "npm" / "node_modules" / "gltf-validator"
needs_validator = pytest.mark.skipif(
    not VALIDATOR.is_dir() or not shutil.which("node"),
    reason="needs node and the pinned gltf-validator (cd tools/npm && npm ci)",
)

FILES = {
    "gltf/one_accessor_two_primitives.gltf": ROOT
    / "fixtures/check/one_accessor_two_primitives.gltf",
    "gltf/two_accessors_one_view.gltf": ROOT / "fixtures/check/two_accessors_one_view.gltf",
    "gltf/clearcoat_normal_without_tangents.gltf": (
        ROOT / "fixtures/check/clearcoat_normal_without_tangents.gltf"
    ),
    "mesh/cube_binary_le.ply": ROOT / "fixtures/ply/cube_binary_le.ply",
    "mesh/ply_truncated.ply": ROOT / "fixtures/bad/ply_truncated.ply",
}
# The validator's error codes (fixtures/check/README.md), and trimesh's verdicts.
VALIDATOR_ERRORS = {
    "gltf/one_accessor_two_primitives.gltf": [],
    "gltf/two_accessors_one_view.gltf": ["MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE"],
    "gltf/clearcoat_normal_without_tangents.gltf": ["MESH_PRIMITIVE_NO_TANGENT_SPACE"],
}
TRIMESH_LOADS = {"mesh/cube_binary_le.ply": True, "mesh/ply_truncated.ply": False}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """The corpus command's records and Markdown report on FILES."""
    tmp = tmp_path_factory.mktemp("corpus")
    for name, source in FILES.items():
        (tmp / "in" / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(source, tmp / "in" / name)
    (tmp / "in" / "SOURCES").write_text("gltf fixtures - fixtures/check\nmesh fixtures - ply\n")
    cmd = [sys.executable, "-m", "raycast_tools", "corpus", tmp / "in", "--raycast", RAYCAST]
    cmd += ["--out", tmp / "corpus.md", "--json", tmp / "records.json"]
    cmd += ["--list", tmp / "files.tsv", "--rays", "200"]
    subprocess.run([str(c) for c in cmd], check=True, cwd=ROOT)
    records = {r["file"]: r for r in json.loads((tmp / "records.json").read_text())}
    return records, (tmp / "corpus.md").read_text(), (tmp / "files.tsv").read_text()


@needs_binary
@needs_validator
def test_validator_verdicts_beside_checks(corpus):
    records, _, _ = corpus
    for name, errors in VALIDATOR_ERRORS.items():
        assert records[name]["validator"]["errors"] == errors, name
        assert records[name]["check"]["errors"] == errors, name


@needs_binary
@needs_validator
def test_trimesh_verdicts_and_depth(corpus):
    records, _, _ = corpus
    for name, loads in TRIMESH_LOADS.items():
        assert records[name]["reference"]["loads"] is loads, name
    good = records["mesh/cube_binary_le.ply"]
    assert good["render"]["status"] == 0
    assert good["info"]["triangles"] == good["reference"]["triangles"] == 12
    assert good["reference"]["depth"]["compared"] and good["reference"]["depth"]["ok"]
    bad = records["mesh/ply_truncated.ply"]
    assert bad["render"]["status"] == 1 and "ply_truncated.ply" in bad["render"]["message"]
    assert bad["check"]["errors"] == ["PLY_TRUNCATED"]


@needs_binary
@needs_validator
def test_report_summary_and_list(corpus):
    _, report, listing = corpus
    summary = next(line for line in report.splitlines() if line.startswith("| **all** |"))
    cells = [c.strip() for c in summary.strip("|").split("|")]
    # files, gltf, obj, ply, stl, usd, valid, refused valid, false check errors, check errors
    # on readable files, missed codes
    assert cells[1:12] == ["5", "3", "0", "2", "0", "0", "2", "0", "0", "0", "0"]
    assert "### Valid files refused by render (0)" in report
    assert (
        "`gltf/two_accessors_one_view.gltf` | 0 | MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE"
        in report
    )
    assert "mesh/cube_binary_le.ply\t" in listing and "\tfixtures\t" in listing


def test_depth_verdicts_tell_geometry_from_numbering():
    from raycast_tools.validate.corpus_report import depth_verdict

    def record(**depth):
        return {"reference": {"depth": depth}}

    assert depth_verdict(record(compared=False)) is None
    assert depth_verdict(record(compared=True, ok=True)) == "agrees"
    numbering = ["prim_agreement", "normal_flipped_max", "object agreement 0.4094"]
    assert depth_verdict(record(compared=True, ok=False, failed_checks=numbering)) == "numbering"
    geometry = ["prim_agreement", "depth_rel_p99"]
    assert depth_verdict(record(compared=True, ok=False, failed_checks=geometry)) == "geometry"
    hits = ["hitmiss_agreement"]
    assert depth_verdict(record(compared=True, ok=False, failed_checks=hits)) == "geometry"
