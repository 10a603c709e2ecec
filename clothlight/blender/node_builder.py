"""Shader nodes added and linked in one call, for the materials built from plain Cycles nodes."""

from __future__ import annotations

import bpy


class NodeBuilder:
    """Adds nodes to ``tree``: an input given as a socket is linked, any other value is set."""

    def __init__(self, tree):
        self.tree = tree

    def node(self, node_type: str, location, inputs=(), **properties):
        """A new ``node_type`` node at ``location``; ``inputs`` fill its inputs by position or, as a
        mapping, by name; ``properties`` are set on the node (``operation``, ``distribution``…)."""
        node = self.tree.nodes.new(node_type)
        node.location = location
        for name, value in properties.items():
            setattr(node, name, value)
        items = inputs.items() if isinstance(inputs, dict) else enumerate(inputs)
        for key, value in items:
            if value is None:
                continue
            if isinstance(value, bpy.types.NodeSocket):
                self.tree.links.new(value, node.inputs[key])
            else:
                node.inputs[key].default_value = value
        return node

    def math(self, operation: str, *inputs, location=(0, 0)):
        """The output socket of a Math node."""
        return self.node("ShaderNodeMath", location, inputs, operation=operation).outputs[0]

    def vector_math(self, operation: str, *inputs, location=(0, 0)):
        """The node of a Vector Math node (DOT_PRODUCT answers on ``outputs["Value"]``, the rest on
        ``outputs[0]``; SCALE takes its factor on ``inputs["Scale"]``)."""
        return self.node("ShaderNodeVectorMath", location, inputs, operation=operation)

    def link(self, socket, target) -> None:
        self.tree.links.new(socket, target)
