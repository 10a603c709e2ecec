"""Scene settings that ClothLight's materials need in Cycles."""

from __future__ import annotations

OSL_DEVICE_NOTE = (
    "ClothLight shaders are OSL, so Cycles renders them on the CPU. OSL on the GPU needs OptiX, "
    "where texture() ignores wrap/filter options and trace() always misses: tables would be read "
    "unfiltered and yarn-to-yarn shadows would be lost."
)


def use_cycles(scene) -> str:
    """Switch ``scene`` to Cycles, its shading system and device left as they are (a yarn material in
    plain nodes renders under either); return a message saying what changed."""
    if scene.render.engine == "CYCLES":
        return "Cycles (already set)"
    scene.render.engine = "CYCLES"
    return "Cycles (render engine → Cycles). The material is plain Cycles nodes: SVM or OSL, CPU or GPU."


def use_cycles_osl_on_cpu(scene) -> str:
    """Switch ``scene`` to Cycles with OSL on the CPU; return a message saying what changed and why."""
    changed = []
    if scene.render.engine != "CYCLES":
        scene.render.engine = "CYCLES"
        changed.append("render engine → Cycles")
    if scene.cycles.device != "CPU":
        scene.cycles.device = "CPU"
        changed.append("device → CPU")
    if not scene.cycles.shading_system:
        scene.cycles.shading_system = True
        changed.append("Open Shading Language on")
    summary = ", ".join(changed) if changed else "already set"
    return f"Cycles OSL on CPU ({summary}). {OSL_DEVICE_NOTE}"
