#!/usr/bin/env python3
"""Generates assets/humanoid.urdf from Winter's anthropometric tables.

Run from the repository root:  python3 assets/humanoid_gen.py > assets/humanoid.urdf
(standard library only). The numbers it uses, and why, are in assets/README.md.

Source of the segment fractions: D. A. Winter, "Biomechanics and Motor Control of Human
Movement", 4th ed., Wiley 2009, Table 4.1 (segment mass / total body mass) and Fig. 4.1
(segment lengths / body height H, after Drillis & Contini).

Every link is built from primitives of uniform density; its inertial block is computed from
those same primitives (mass from Winter, COM and inertia tensor from the shapes), so the
inertias are consistent with the collision geometry.
"""

import math

H = 1.75  # body height, m
M = 70.0  # body mass, kg

# Winter Table 4.1, segment mass / total body mass.
FRAC_HEAD_NECK = 0.081
FRAC_THORAX = 0.216
FRAC_ABDOMEN = 0.139
FRAC_PELVIS = 0.142
FRAC_TOTAL_ARM = 0.050  # upper arm + forearm + hand
FRAC_THIGH = 0.100
FRAC_LEG = 0.0465  # shank
FRAC_FOOT = 0.0145

# Winter Fig. 4.1, heights / lengths as a fraction of H.
Z_SHOULDER = 0.818 * H
Z_HIP = 0.530 * H  # greater trochanter
Z_KNEE = 0.285 * H
Z_ANKLE = 0.039 * H
ARM_LENGTH = (0.186 + 0.146 + 0.108) * H  # upper arm + forearm + hand
FOOT_LENGTH = 0.152 * H
FOOT_WIDTH = 0.055 * H
SHOULDER_WIDTH = 0.259 * H

# Design choices (not in Winter), documented in assets/README.md.
HIP_Y = 0.10  # lateral offset of each hip joint from the mid-line, m
THIGH_R = 0.065
SHANK_R = 0.045
ARM_R = 0.040
FOOT_H = 0.060  # foot box height; its top sits a little below the ankle axis
HEEL_FRACTION = 0.25  # ankle axis lies a quarter of the foot length in front of the heel
SHOULDER_LINK_MASS = 0.10  # light intermediate link of the 2-DOF shoulder, taken from the arm
SHOULDER_LINK_R = 0.03
TORSO_DEPTH = 0.20
PELVIS_WIDTH, PELVIS_BOTTOM, PELVIS_TOP = 0.30, -0.04, 0.10  # torso frame (origin: hip centre)
TRUNK_WIDTH = 0.34
HEAD_R = 0.105

# Joint limits (paper, sec. 5) and effort limits (see README).
HIP_LIMITS = (math.radians(-90.0), math.radians(30.0))
KNEE_LIMITS = (math.radians(5.0), math.radians(90.0))
ANKLE_LIMITS = (math.radians(-20.0), math.radians(20.0))
HIP_EFFORT, KNEE_EFFORT, ANKLE_EFFORT = 150.0, 150.0, 120.0
LEG_DAMPING = 0.5
SHOULDER_PITCH_LIMITS = (math.radians(-60.0), math.radians(60.0))
SHOULDER_ROLL_LIMITS = (math.radians(-10.0), math.radians(60.0))
SHOULDER_DAMPING = 1.5


def box_inertia(m, sx, sy, sz):
    return [m * (sy * sy + sz * sz) / 12.0, m * (sx * sx + sz * sz) / 12.0, m * (sx * sx + sy * sy) / 12.0]


def cylinder_inertia(m, r, length):  # axis along z
    i = m * (3.0 * r * r + length * length) / 12.0
    return [i, i, m * r * r / 2.0]


def sphere_inertia(m, r):
    i = 0.4 * m * r * r
    return [i, i, i]


def composite(parts):
    """parts: list of (mass, centre [x,y,z], principal diag inertia about own centre, axis-aligned)."""
    mass = sum(p[0] for p in parts)
    com = [sum(p[0] * p[1][k] for p in parts) / mass for k in range(3)]
    inertia = [[0.0] * 3 for _ in range(3)]
    for m, c, diag in parts:
        d = [c[k] - com[k] for k in range(3)]
        dd = sum(x * x for x in d)
        for a in range(3):
            for b in range(3):
                inertia[a][b] += (diag[a] if a == b else 0.0) + m * ((dd if a == b else 0.0) - d[a] * d[b])
    return mass, com, inertia


def f(x):
    s = f"{x:.6g}"
    return "0" if s in ("-0", "0") else s


def v3(v):
    return " ".join(f(x) for x in v)


def inertial_xml(mass, com, inertia):
    i = inertia
    return (
        f'    <inertial>\n      <origin xyz="{v3(com)}" rpy="0 0 0"/>\n      <mass value="{f(mass)}"/>\n'
        f'      <inertia ixx="{f(i[0][0])}" ixy="{f(i[0][1])}" ixz="{f(i[0][2])}" '
        f'iyy="{f(i[1][1])}" iyz="{f(i[1][2])}" izz="{f(i[2][2])}"/>\n    </inertial>\n'
    )


def diag(d):
    return [[d[0], 0, 0], [0, d[1], 0], [0, 0, d[2]]]


def collision_xml(xyz, geom, rpy=(0, 0, 0)):
    return (
        f'    <collision>\n      <origin xyz="{v3(xyz)}" rpy="{v3(rpy)}"/>\n'
        f"      <geometry>{geom}</geometry>\n    </collision>\n"
    )


def visual_xml(xyz, geom, material):
    return (
        f'    <visual>\n      <origin xyz="{v3(xyz)}" rpy="0 0 0"/>\n'
        f'      <geometry>{geom}</geometry>\n      <material name="{material}"/>\n    </visual>\n'
    )


def link(name, mass, com, inertia, shapes, material):
    out = f'  <link name="{name}">\n' + inertial_xml(mass, com, inertia)
    for xyz, geom in shapes:
        out += visual_xml(xyz, geom, material)
        out += collision_xml(xyz, geom)
    return out + "  </link>\n"


def joint(name, parent, child, xyz, axis, limits, effort, damping, velocity=30.0):
    return (
        f'  <joint name="{name}" type="revolute">\n'
        f'    <origin xyz="{v3(xyz)}" rpy="0 0 0"/>\n'
        f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
        f'    <axis xyz="{v3(axis)}"/>\n'
        f'    <limit lower="{f(limits[0])}" upper="{f(limits[1])}" effort="{f(effort)}" velocity="{f(velocity)}"/>\n'
        f'    <dynamics damping="{f(damping)}" friction="0"/>\n'
        f"  </joint>\n"
    )


def main():
    out = []
    thigh_len = Z_HIP - Z_KNEE
    shank_len = Z_KNEE - Z_ANKLE
    z_shoulder = Z_SHOULDER - Z_HIP  # in the torso frame (origin at hip-joint height)
    trunk_bottom, trunk_top = PELVIS_TOP, z_shoulder + 0.04
    head_z = H - HEAD_R - Z_HIP

    # Torso: pelvis box, thorax+abdomen box, head+neck sphere.
    pelvis = (TORSO_DEPTH, PELVIS_WIDTH, PELVIS_TOP - PELVIS_BOTTOM)
    pelvis_c = (0.0, 0.0, (PELVIS_TOP + PELVIS_BOTTOM) / 2)
    trunk = (TORSO_DEPTH, TRUNK_WIDTH, trunk_top - trunk_bottom)
    trunk_c = (0.0, 0.0, (trunk_top + trunk_bottom) / 2)
    head_c = (0.0, 0.0, head_z)
    m_pelvis, m_trunk, m_head = FRAC_PELVIS * M, (FRAC_THORAX + FRAC_ABDOMEN) * M, FRAC_HEAD_NECK * M
    torso_mass, torso_com, torso_inertia = composite(
        [
            (m_pelvis, pelvis_c, box_inertia(m_pelvis, *pelvis)),
            (m_trunk, trunk_c, box_inertia(m_trunk, *trunk)),
            (m_head, head_c, sphere_inertia(m_head, HEAD_R)),
        ]
    )

    out.append('<?xml version="1.0"?>\n')
    out.append(
        "<!--\n"
        "  esrl humanoid: 1.75 m, 70 kg, generated by assets/humanoid_gen.py (do not edit by hand).\n"
        "  Segment mass fractions and lengths: D. A. Winter, Biomechanics and Motor Control of Human\n"
        "  Movement, 4th ed. (2009), Table 4.1 and Fig. 4.1:\n"
        f"    head+neck 0.081, thorax 0.216, abdomen 0.139, pelvis 0.142 (torso {f(torso_mass)} kg),\n"
        f"    total arm 0.050 ({f(FRAC_TOTAL_ARM * M)} kg incl. a {f(SHOULDER_LINK_MASS)} kg shoulder link),\n"
        f"    thigh 0.100 ({f(FRAC_THIGH * M)} kg), leg 0.0465 ({f(FRAC_LEG * M)} kg), foot 0.0145 ({f(FRAC_FOOT * M)} kg);\n"
        "    heights: shoulder 0.818 H, hip 0.530 H, knee 0.285 H, ankle 0.039 H; arm 0.440 H;\n"
        "    foot 0.152 H x 0.055 H; shoulder breadth 0.259 H.\n"
        "  Inertias: uniform solids matching the collision primitives (not Winter's radii of gyration).\n"
        "  Frames (REP-103): x forward along the track, y left, z up. The paper calls forward y and\n"
        "  lateral x. Zero pose: standing straight, arms hanging. Positive pitch (axis +y) swings a\n"
        "  segment backwards: hip extension, knee flexion, ankle plantarflexion are positive.\n"
        "  Shoulder roll is abduction-positive on both sides (right axis is -x).\n"
        "-->\n"
    )
    out.append('<robot name="esrl_humanoid">\n')
    out.append('  <material name="skin"><color rgba="0.85 0.7 0.6 1"/></material>\n')
    out.append('  <material name="cloth"><color rgba="0.2 0.3 0.6 1"/></material>\n')
    out.append('  <material name="shoe"><color rgba="0.15 0.15 0.15 1"/></material>\n')

    torso_shapes = [
        (pelvis_c, f'<box size="{v3(pelvis)}"/>'),
        (trunk_c, f'<box size="{v3(trunk)}"/>'),
        (head_c, f'<sphere radius="{f(HEAD_R)}"/>'),
    ]
    out.append(link("torso", torso_mass, torso_com, torso_inertia, torso_shapes, "cloth"))

    arm_mass = FRAC_TOTAL_ARM * M - SHOULDER_LINK_MASS
    for side, sign in (("left", 1.0), ("right", -1.0)):
        # Arm: passive 2-DOF shoulder built from two revolute joints through a light link.
        out.append(
            f'  <link name="{side}_shoulder">\n'
            + inertial_xml(SHOULDER_LINK_MASS, (0, 0, 0), diag(sphere_inertia(SHOULDER_LINK_MASS, SHOULDER_LINK_R)))
            + "  </link>\n"
        )
        out.append(
            link(
                f"{side}_arm",
                arm_mass,
                (0, 0, -ARM_LENGTH / 2),
                diag(cylinder_inertia(arm_mass, ARM_R, ARM_LENGTH)),
                [((0, 0, -ARM_LENGTH / 2), f'<cylinder radius="{f(ARM_R)}" length="{f(ARM_LENGTH)}"/>')],
                "skin",
            )
        )
        # Leg: thigh, shank, foot.
        m_thigh, m_shank, m_foot = FRAC_THIGH * M, FRAC_LEG * M, FRAC_FOOT * M
        out.append(
            link(
                f"{side}_thigh",
                m_thigh,
                (0, 0, -thigh_len / 2),
                diag(cylinder_inertia(m_thigh, THIGH_R, thigh_len)),
                [((0, 0, -thigh_len / 2), f'<cylinder radius="{f(THIGH_R)}" length="{f(thigh_len)}"/>')],
                "cloth",
            )
        )
        out.append(
            link(
                f"{side}_shank",
                m_shank,
                (0, 0, -shank_len / 2),
                diag(cylinder_inertia(m_shank, SHANK_R, shank_len)),
                [((0, 0, -shank_len / 2), f'<cylinder radius="{f(SHANK_R)}" length="{f(shank_len)}"/>')],
                "cloth",
            )
        )
        foot = (FOOT_LENGTH, FOOT_WIDTH, FOOT_H)
        foot_c = (FOOT_LENGTH * (0.5 - HEEL_FRACTION), 0.0, -Z_ANKLE + FOOT_H / 2)
        out.append(
            link(f"{side}_foot", m_foot, foot_c, diag(box_inertia(m_foot, *foot)), [(foot_c, f'<box size="{v3(foot)}"/>')], "shoe")
        )

    for side, sign in (("left", 1.0), ("right", -1.0)):
        shoulder_xyz = (0.0, sign * SHOULDER_WIDTH / 2, z_shoulder)
        out.append(
            joint(f"{side}_shoulder_pitch", "torso", f"{side}_shoulder", shoulder_xyz, (0, 1, 0), SHOULDER_PITCH_LIMITS, 0.0, SHOULDER_DAMPING)
        )
        out.append(
            joint(f"{side}_shoulder_roll", f"{side}_shoulder", f"{side}_arm", (0, 0, 0), (sign, 0, 0), SHOULDER_ROLL_LIMITS, 0.0, SHOULDER_DAMPING)
        )
        out.append(joint(f"{side}_hip", "torso", f"{side}_thigh", (0.0, sign * HIP_Y, 0.0), (0, 1, 0), HIP_LIMITS, HIP_EFFORT, LEG_DAMPING))
        out.append(joint(f"{side}_knee", f"{side}_thigh", f"{side}_shank", (0, 0, -thigh_len), (0, 1, 0), KNEE_LIMITS, KNEE_EFFORT, LEG_DAMPING))
        out.append(joint(f"{side}_ankle", f"{side}_shank", f"{side}_foot", (0, 0, -shank_len), (0, 1, 0), ANKLE_LIMITS, ANKLE_EFFORT, LEG_DAMPING))
    out.append("</robot>\n")
    print("".join(out), end="")


if __name__ == "__main__":
    main()
