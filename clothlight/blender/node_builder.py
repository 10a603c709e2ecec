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
        return self.node_inputs(node, inputs)

    def node_inputs(self, node, inputs):
        """Fill ``node``'s inputs (by position, or by name from a mapping; None skips); returns it."""
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

    def tangent_frame(self, normal, tangent, location=(0, 0)):
        """The frame of a surface whose ``tangent`` (a yarn axis, a warp) is made normal to the unit
        ``normal``: the sockets of x = normalize(t − (t·n) n) and y = n × x."""
        x0, y0 = location
        along = self.vector_math("DOT_PRODUCT", tangent, normal, location=(x0, y0)).outputs["Value"]
        normal_part = self.vector_math("SCALE", normal, location=(x0 + 150, y0))
        self.link(along, normal_part.inputs["Scale"])
        in_plane = self.vector_math("SUBTRACT", tangent, normal_part.outputs[0], location=(x0 + 300, y0))
        x = self.vector_math("NORMALIZE", in_plane.outputs[0], location=(x0 + 450, y0)).outputs[0]
        y = self.vector_math("CROSS_PRODUCT", normal, x, location=(x0 + 600, y0 - 100)).outputs[0]
        return x, y

    def add_shaders(self, closures, x=0):
        """The socket of the sum of the shader sockets ``closures`` (Add Shader nodes in a chain)."""
        total = closures[0]
        for index, closure in enumerate(closures[1:]):
            total = self.node("ShaderNodeAddShader", (x, -150 * index), (total, closure)).outputs[0]
        return total
