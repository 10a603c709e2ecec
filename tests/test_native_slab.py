"""The native slab library (precompute/transport/native.py, precompute/slab/native.py): numba's slab task
compiled ahead of time, which the slab command runs without importing numba or NumPy, with the numba
kernel's answer bit for bit."""

import json
import os
import subprocess
import sys

import numba
import pytest

from precompute.slab import native as native_slab
from precompute.__main__ import main
from precompute.errors import ParameterError
from precompute.cache.kernel_sources import sources_digest
from precompute.transport import simulate_hg_slab
from precompute.transport.native import build_native_slab

from tests.helpers import slow_fixture

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
@slow_fixture
def native_slab_library(tmp_path_factory):
    """A library built for the current sources in a folder of its own, as NUMBA_CACHE_DIR would place it."""
    folder = tmp_path_factory.mktemp("native")
    return build_native_slab(native_slab.library_path(folder=folder))


@pytest.mark.parametrize(("albedo", "g", "tau", "index", "paths", "seed", "threads"), [
    (0.9, 0.75, 2.0, 1.0, 20_000, 0, 1),  # van de Hulst's slab, matched boundary
    (0.9, 0.75, 2.0, 1.5, 20_001, 7, 2),  # Fresnel boundaries, paths not a multiple of the tasks, two threads
    (0.3, -0.5, 0.5, 1.33, 5_000, 3, 2),  # absorbing, back-scattering: roulette every 4th collision
    (1.0, 0.0, 8.0, 1.0, 3_000, 2**62, 1),  # no absorption, isotropic, thick; a seed near the top of its range
])
def test_the_library_gives_the_numba_kernels_answer_bit_for_bit(native_slab_library, albedo, g, tau, index, paths,
                                                                seed, threads):
    library = native_slab.load_library(native_slab_library)
    native = native_slab.simulate_hg_slab_native(library, albedo, g, tau, index, paths=paths, seed=seed,
                                                 threads=threads)
    expected = simulate_hg_slab(albedo, g, tau, index, paths=paths, seed=seed, threads=1).summary()
    assert native == expected
    assert native["events"] > paths // 2 and 0.0 < native["R_total"] < 1.0 and 0.0 < native["T_total"] < 1.0


def test_the_slab_command_runs_without_numba_or_numpy_where_the_library_is_built(native_slab_library):
    command = ["slab", "--albedo", "0.8", "--g", "0.6", "--tau", "1.5", "--n", "1.4", "--paths", "4000", "--seed",
               "5", "--engine", "native", "--json"]
    script = ("import sys; from precompute.__main__ import main; code = main(sys.argv[1:]); "
              "assert 'numba' not in sys.modules and 'numpy' not in sys.modules, 'imported'; sys.exit(code)")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(native_slab_library.parent))
    done = subprocess.run([sys.executable, "-c", script, *command], cwd=REPO, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    printed = json.loads(done.stdout)
    expected = simulate_hg_slab(0.8, 0.6, 1.5, 1.4, paths=4000, seed=5).summary()
    assert printed == {key: expected[key] for key in printed} and len(printed) == 13


def test_without_a_library_for_these_sources_the_command_uses_numba_or_says_what_to_run(tmp_path, monkeypatch,
                                                                                        capsys):
    stale = native_slab.library_path(digest="0" * 64, folder=tmp_path)
    stale.write_bytes(b"a library built from other sources")
    monkeypatch.setattr(native_slab, "library_folder", lambda: tmp_path)
    assert native_slab.load_library() is None  # named by another digest: never loaded
    assert native_slab.library_path() == native_slab.library_path(sources_digest(), tmp_path) != stale
    arguments = ["slab", "--albedo", "0.5", "--g", "0.2", "--tau", "1", "--paths", "500", "--json", "--engine"]
    assert main(arguments + ["auto"]) == 0
    assert json.loads(capsys.readouterr().out)["R_total"] == simulate_hg_slab(0.5, 0.2, 1.0, 1.0, paths=500).R_total[0]
    assert main(arguments + ["native"]) == 2
    assert "make setup" in capsys.readouterr().err


def test_the_thread_limit_is_numbas_and_is_enforced(native_slab_library):
    assert native_slab.available_threads() == numba.config.NUMBA_NUM_THREADS
    library = native_slab.load_library(native_slab_library)
    for threads in (0, native_slab.available_threads() + 1, 1.0, True):
        with pytest.raises(ParameterError, match="threads"):
            native_slab.simulate_hg_slab_native(library, 0.9, 0.5, 1.0, 1.0, paths=100, seed=0, threads=threads)
