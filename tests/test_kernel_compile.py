"""The ahead-of-time kernel step (``python -m precompute.transport.compile``, run by ``make setup``)
compiles what real jobs call: after it, a yarn bake's transport, a slab and the absorption
reweighting compile no new specialisation."""

import numpy as np

from precompute.optics.medium import load_preset
from precompute.optics.coefficients import medium_optics
from precompute.transport import TransportGrids, YarnGeometry, _kernels, simulate_hg_slab, simulate_yarn
from precompute.transport.absorption import absorption_steps, reweighted_transport
from precompute.transport.compile import compile_kernels

KERNELS = (_kernels.slab_kernel, _kernels.slab_results, _kernels.yarn_kernel, _kernels.beam_kernel,
           _kernels.interpolate_steps)


def test_real_jobs_after_the_compile_step_use_its_specialisations():
    assert compile_kernels() == ["slab", "yarn", "absorption reweighting", "parallel beam", "direction grids"]
    before = [len(kernel.signatures) for kernel in KERNELS]
    assert all(before)
    optics = medium_optics(load_preset("paper_2008"))
    geometry = YarnGeometry(0.1, optics.boundary_index)
    steps = absorption_steps(optics.mu_a, optics.mu_a * 2)
    transport = simulate_yarn(optics, geometry, TransportGrids(8, 2, 3), paths_per_cell=16, seed=1,
                              extra_absorption_per_mm=steps)
    reweighted_transport(transport, optics.mu_a * 1.5)
    simulate_hg_slab(0.8, 0.3, 0.5, 1.33, paths=100)
    assert [len(kernel.signatures) for kernel in KERNELS] == before
    assert np.isfinite(transport.exit_fraction).all()
