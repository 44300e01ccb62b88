"""Two-shelf shop facts (model-facts.md section 5.4)."""

# joint, parent, child, xyz, rpy
JOINTS = [
    ('shelf_1_joint', 'room_link', 'shelf_1_base', '4.3223 -0.2415761 0.08515', '0 0 -1.5756'),
    ('shelf_1_base_back_joint', 'shelf_1_base', 'shelf_1_back', '0 0.365 1', '0 0 0'),
    ('shelf_1_level_0_joint', 'shelf_1_base', 'shelf_1_level_0_link', '0 -0.06 0.10665', '0 0 0'),
    ('shelf_1_level_1_joint', 'shelf_1_base', 'shelf_1_level_1_link', '0 0 0.50965', '0 0 0'),
    ('shelf_1_level_2_joint', 'shelf_1_base', 'shelf_1_level_2_link', '0 0 0.84465', '0 0 0'),
    ('shelf_1_level_3_joint', 'shelf_1_base', 'shelf_1_level_3_link', '0 0 1.22265', '0 0 0'),
    ('shelf_1_level_4_joint', 'shelf_1_base', 'shelf_1_level_4_link', '0 0 1.53565', '0 0 0'),
    ('shelf_1_level_5_joint', 'shelf_1_base', 'shelf_1_level_5_link', '0 0 1.86865', '0 0 0'),
    ('shelf_2_joint', 'room_link', 'shelf_2_base', '1.75 -1.45 0.08515', '0 0 3.09652'),
    ('shelf_2_base_left_joint', 'shelf_2_base', 'shelf_2_left_side', '-0.475 0 0.7225', '0 0 0'),
    ('shelf_2_base_right_joint', 'shelf_2_base', 'shelf_2_right_side', '0.475 0 0.7225', '0 0 0'),
    ('shelf_2_base_back_joint', 'shelf_2_base', 'shelf_2_back', '0 0.275 0.7725', '0 0 0'),
    ('shelf_2_level_0_joint', 'shelf_2_base', 'shelf_2_level_0_link', '0 0 0.0925', '0 0 0'),
    ('shelf_2_shelf_2_level_1_joint', 'shelf_2_base', 'shelf_2_shelf_2_level_1_link', '0 0.0 0.374', '0 0 0'),
    ('shelf_2_shelf_2_level_2_joint', 'shelf_2_base', 'shelf_2_shelf_2_level_2_link', '0 0.0 0.624', '0 0 0'),
    ('shelf_2_shelf_2_level_3_joint', 'shelf_2_base', 'shelf_2_shelf_2_level_3_link', '0 0.0 0.864', '0 0 0'),
    ('shelf_2_shelf_2_level_4_joint', 'shelf_2_base', 'shelf_2_shelf_2_level_4_link', '0 0.0 1.17', '0 0 0'),
    ('shelf_2_shelf_2_level_5_joint', 'shelf_2_base', 'shelf_2_shelf_2_level_5_link', '0 0.0 1.42', '0 0 0'),
]

# link, collision geometry (link frame), origin xyz / rpy, world AABB min, world AABB max
COLLISION = [
    ('shelf_1_base', 'box 1.1 1.05 0.173', '0 0 0 / 0 0 0', '3.795 -0.7941 -0.00135', '4.85 0.3109 0.1716'),
    ('shelf_1_back', 'box 1.04 0.12 2', '0 0 0 / 0 0 0', '4.625 -0.7636 0.08515', '4.75 0.277 2.085'),
    ('shelf_1_level_0_link', 'box 1 0.78 0.043', '0 0 0 / 0 0 0', '3.87 -0.7432 0.1703', '4.655 0.2606 0.2133'),
    ('shelf_1_level_1_link', 'box 0.988 0.65 0.043', '0 0 0 / 0 0 0', '3.995 -0.7371 0.5733', '4.65 0.254 0.6163'),
    ('shelf_1_level_2_link', 'box 0.988 0.65 0.043', '0 0 0 / 0 0 0', '3.995 -0.7371 0.9083', '4.65 0.254 0.9513'),
    ('shelf_1_level_3_link', 'box 0.988 0.65 0.043', '0 0 0 / 0 0 0', '3.995 -0.7371 1.286', '4.65 0.254 1.329'),
    ('shelf_1_level_4_link', 'box 0.988 0.65 0.043', '0 0 0 / 0 0 0', '3.995 -0.7371 1.599', '4.65 0.254 1.642'),
    ('shelf_1_level_5_link', 'box 0.988 0.65 0.043', '0 0 0 / 0 0 0', '3.995 -0.7371 1.932', '4.65 0.254 1.975'),
    ('shelf_2_base', 'box 1.1 0.8 0.145', '0 0 0 / 0 0 0', '1.183 -1.874 0.01265', '2.317 -1.026 0.1577'),
    ('shelf_2_left_side', 'box 0.05 0.54 1.6', '0 0 0 / 0 0 0', '2.187 -1.742 0.00765', '2.262 -1.201 1.608'),
    ('shelf_2_right_side', 'box 0.05 0.54 1.6', '0 0 0 / 0 0 0', '1.238 -1.699 0.00765', '1.313 -1.158 1.608'),
    ('shelf_2_back', 'box 1 0.05 1.45', '0 0 0 / 0 0 0', '1.237 -1.772 0.1327', '2.238 -1.677 1.583'),
    ('shelf_2_level_0_link', 'box 0.992 0.54 0.043', '0 0 0 / 0 0 0', '1.242 -1.742 0.1562', '2.258 -1.158 0.1991'),
    ('shelf_2_shelf_2_level_1_link', 'box 0.992 0.435 0.043', '0 0 0 / 0 0 0', '1.245 -1.69 0.4376', '2.255 -1.21 0.4807'),
    ('shelf_2_shelf_2_level_2_link', 'box 0.992 0.435 0.043', '0 0 0 / 0 0 0', '1.245 -1.69 0.6876', '2.255 -1.21 0.7306'),
    ('shelf_2_shelf_2_level_3_link', 'box 0.992 0.435 0.043', '0 0 0 / 0 0 0', '1.245 -1.69 0.9276', '2.255 -1.21 0.9706'),
    ('shelf_2_shelf_2_level_4_link', 'box 0.992 0.435 0.043', '0 0 0 / 0 0 0', '1.245 -1.69 1.234', '2.255 -1.21 1.277'),
    ('shelf_2_shelf_2_level_5_link', 'box 0.992 0.435 0.043', '0 0 0 / 0 0 0', '1.245 -1.69 1.484', '2.255 -1.21 1.527'),
]
