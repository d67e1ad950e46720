"""The linear stage's key (sarfe.pipeline.model.stage.linear_model_key): the SHA-256 of what the
stage depends on — the same for a change the stage does not see (contact law parameters, damping,
force amplitudes, frequencies under a given cutoff), another for one it does (mesh, cutoff,
contact nodes). And the one SHA-256 helper it hashes with (sarfe.util.hashing)."""
import hashlib
from pathlib import Path

from sarfe.case.read import load_case
from sarfe.pipeline.model.stage import linear_model_key
from sarfe.util.hashing import file_sha256, sha256_hex

CASES = Path(__file__).resolve().parents[3] / "cases"


def test_sha256_helper_is_sha256():
    assert sha256_hex("abc") == ("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61"
                                 "f20015ad")                        # FIPS 180-2, appendix B.1
    assert sha256_hex("a", b"bc") == sha256_hex("abc") and len(sha256_hex("abc", length=16)) == 16
    path = CASES / "rattle_rig.yaml"
    assert file_sha256(path) == hashlib.sha256(path.read_bytes()).hexdigest()


def test_key_follows_what_the_stage_depends_on():
    base = load_case(CASES / "rattle_rig.yaml").with_reduction(cutoff_hz=400.0)
    key = linear_model_key(base)
    same = (base.with_contact(0, normal_stiffness_N_m=1e6, tolerance_m=3e-4),
            base.with_solver(harmonics=7, samples_per_period=256))
    assert all(linear_model_key(case) == key for case in same)
    other = (base.with_reduction(cutoff_hz=500.0), base.with_generator(mesh_size_m=0.02))
    assert len({key, *(linear_model_key(case) for case in other)}) == 3
    # without a given cutoff the default one (margin · H · f_max) follows H: another stage
    free = load_case(CASES / "rattle_rig.yaml")
    assert linear_model_key(free) != linear_model_key(free.with_solver(harmonics=7,
                                                                       samples_per_period=256))
