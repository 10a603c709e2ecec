"""Names of the mesh attributes the woven sample carries and the ClothLight shaders read."""

#: Unit tangent along the yarn axis, object space (FLOAT_VECTOR, point domain).
YARN_TANGENT = "yarn_tangent"
#: Macroscopic cloth normal, object space (FLOAT_VECTOR, point domain).
CLOTH_NORMAL = "cloth_normal"
#: Index of the yarn a vertex belongs to (INT, point domain).
YARN_ID = "yarn_id"
#: 1 for warp yarns, 0 for weft yarns (INT, point domain).
IS_WARP = "is_warp"
#: UV map: u along the yarn axis, v around its circumference.
YARN_UV = "YarnUV"
