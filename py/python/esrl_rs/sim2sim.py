"""Sim-to-sim: the walking task rebuilt on MuJoCo from the same URDF, to run an esrl policy
in a second, independent physics engine before trusting its walk.

    pip install "./py[mujoco]"          # or: pip install mujoco
    python -m esrl_rs.sim2sim results/walking/flagship --episodes 10

:class:`MujocoWalk` is the task of a run's ``[walk]`` settings on MuJoCo: the same URDF (the
embedded humanoid or the run's ``urdf``) with its root on a free joint and a ground plane,
the same observation (every entry computed from MuJoCo's state as ``esrl-sim`` computes it
from Rapier's, with the same fixed scaling and gait clock), the same action mapping
(joint-angle targets within ``target.range`` of the standing pose, or torques), the same
servo law (``τ = clamp(kp·(q* − q) − kd·q̇, ±effort)`` at every physics step), control period
and physics step, armature on the actuated joints, the same initial states (the Rust
environment is reset with the same seed and its state copied: joint angles and velocities,
the torso's pose, the clock's phase) and the same fall and finish rules. :func:`cross_check`
runs a policy in both engines from the same starts and reports the gait metrics of
``esrl_rs.metrics`` side by side.

**What matches and what cannot.** Masses, inertias, joint axes and limits, damping and
friction come from the URDF in both; gravity, friction coefficient (1; MuJoCo takes the
larger of two geoms' coefficients, Rapier their mean, equal here), time step and substeps are
set alike. The contact models differ (Rapier: contacts solved by impulses, one solver
iteration per step, made soft as a spring of 60 Hz and damping ratio 10 that corrects
penetrations beyond 5 mm (``physics.contact_frequency``); MuJoCo: soft contacts with its
default solver reference and impedance), as do the joint-limit models (Rapier: a hard limit,
with torques into it faded over the last 2° under ``fade``; MuJoCo: a soft limit constraint
and the full torque; ``results/mujoco-limits`` tried the fade on MuJoCo's side too) and the
servo (Rapier integrates it implicitly inside its solver; here it is an explicit torque per
physics step, stable at these gains: ω = √(kp/I) ≈ 55 rad/s, ω·h ≈ 0.34). A policy that
walks in both has learned a gait, not a solver artifact; one that walks in one only depends
on what differs.

Three of MuJoCo's own settings can be chosen, to see whether a result depends on them:
``cone`` (:data:`CONES`: MuJoCo's default ``pyramidal`` friction cone, or ``elliptic``, the
shape of Rapier's, which caps the tangential impulse's magnitude), ``servo``
(:data:`SERVOS`: the explicit torque above, or MuJoCo position actuators of the same gains
and torque limit, their damping integrated implicitly as Rapier integrates its servo) and
``limits`` (:data:`LIMITS`). MuJoCo's default joint limit (``soft``: ``solref`` 0.02 s,
``solimp`` 0.9–0.95) is a spring that torque can push through: a torque policy pressing its
joints into their stops bends them 13.5–34.9° past (``results/mujoco-limits``). ``stiff``
is the stiffest limit MuJoCo's integrator allows at this step (``solref`` time constant two
physics steps, ``solimp`` 0.99–0.999): 2.5–7.2° past under the same walks, as in esrl
(Rapier: 2.1–5.7°). Every summary says how far the joints went
(``past_limit_deg``: the largest angle past a URDF limit over the episodes, any actuated
joint), in both engines.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import xml.etree.ElementTree as ET
from typing import Any, Dict, List, Mapping, Optional, Sequence

import numpy as np

from . import _native, metrics

__all__ = ["MujocoWalk", "cross_check", "cross_checks", "main", "CONES", "SERVOS", "LIMITS"]

#: MuJoCo's friction cones: ``pyramidal`` (its default) or ``elliptic``.
CONES = ("pyramidal", "elliptic")
#: How the joint-angle servo is applied: ``explicit`` (the torque computed from the state at
#: each physics step) or ``actuator`` (MuJoCo position actuators, damping integrated
#: implicitly).
SERVOS = ("explicit", "actuator")
#: MuJoCo's joint-limit constraint: ``soft`` (its default) or ``stiff`` (module docs).
LIMITS = ("soft", "stiff")
#: ``solref`` and ``solimp`` of a ``stiff`` limit: the time constant in physics steps (MuJoCo
#: raises a shorter one to two steps), damping ratio 1, impedance 0.99 to 0.999 over 1 mm
#: (1 mrad for a hinge).
_STIFF_STEPS, _STIFF_SOLIMP = 2.0, (0.99, 0.999, 0.001)


def _floating_urdf(text: str) -> str:
    """The URDF with its root link on a free joint (MuJoCo welds a URDF's root to the world
    otherwise), as a file path."""
    root = ET.fromstring(text)
    children = {j.find("child").get("link") for j in root.findall("joint")}
    roots = [l.get("name") for l in root.findall("link") if l.get("name") not in children]
    if len(roots) != 1:
        raise ValueError(f"expected one root link, found {roots}")
    ET.SubElement(root, "link", name="mj_world")
    joint = ET.SubElement(root, "joint", name="mj_float", type="floating")
    ET.SubElement(joint, "parent", link="mj_world")
    ET.SubElement(joint, "child", link=roots[0])
    path = os.path.join(tempfile.mkdtemp(prefix="esrl-sim2sim-"), "floating.urdf")
    ET.ElementTree(root).write(path)
    return path


def _quat_to_mat(q_xyzw: Sequence[float]) -> np.ndarray:
    x, y, z, w = q_xyzw
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


class MujocoWalk:
    """The walking task of ``walk_config`` (a run's ``[walk]`` as a dict) on MuJoCo (module
    docs). ``reset(seed)`` starts from the state the Rust environment resets to with that
    seed; ``step(action)`` returns ``(obs, terminated, truncated, sample)``, ``sample`` one
    step of the gait trace."""

    def __init__(self, walk_config: Mapping[str, Any], cone: str = "pyramidal",
                 servo: str = "explicit", limits: str = "soft") -> None:
        import mujoco

        if cone not in CONES:
            raise ValueError(f"cone {cone!r}: expected one of {', '.join(CONES)}")
        if servo not in SERVOS:
            raise ValueError(f"servo {servo!r}: expected one of {', '.join(SERVOS)}")
        if limits not in LIMITS:
            raise ValueError(f"limits {limits!r}: expected one of {', '.join(LIMITS)}")
        self.limits = limits

        self.mujoco = mujoco
        self.rust = _native.EnvCore.walk(dict(walk_config))
        self.cfg: Dict[str, Any] = self.rust.config
        if self.cfg.get("perturb"):
            raise ValueError("sim2sim rebuilds the undisturbed task; drop [walk.perturb]")
        urdf = self.cfg.get("urdf")
        if urdf:
            with open(urdf, encoding="utf-8") as f:
                text = f.read()
        else:
            text = _native.HUMANOID_URDF
        spec = mujoco.MjSpec.from_file(_floating_urdf(text))
        physics = self.cfg["physics"]
        self.substeps = int(physics["substeps"])
        self.ts = float(self.cfg["control_period"])
        self.h = self.ts / self.substeps
        spec.option.timestep = self.h
        spec.option.gravity = [0.0, 0.0, -float(physics["gravity"])]
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        spec.option.cone = (mujoco.mjtCone.mjCONE_ELLIPTIC if cone == "elliptic"
                            else mujoco.mjtCone.mjCONE_PYRAMIDAL)
        names = self.rust.action_names
        self.servo = servo if self.cfg["action"] == "target" else "explicit"
        if self.servo == "actuator":
            kp = float(self.cfg["target"]["stiffness"])
            kd = float(self.cfg["target"]["damping"])
            for n, e in zip(names, self.rust.effort_limits):
                a = spec.add_actuator()
                a.name, a.target, a.trntype = n, n, mujoco.mjtTrn.mjTRN_JOINT
                a.set_to_position(kp=kp, kv=kd)
                a.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
                a.forcerange = [-float(e), float(e)]
        plane = spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[200, 200, 0.1])
        plane.friction = [float(physics["friction"]), 0.005, 0.0001]
        plane.contype, plane.conaffinity = 0, 1
        m = spec.compile()
        # Robot geoms touch the ground only (esrl's self_collisions = false).
        for g in range(m.ngeom):
            if m.geom_type[g] != mujoco.mjtGeom.mjGEOM_PLANE:
                m.geom_contype[g], m.geom_conaffinity[g] = 1, 0
                m.geom_friction[g][0] = float(physics["friction"])
        if limits == "stiff":
            for j in range(m.njnt):
                if m.jnt_limited[j]:
                    m.jnt_solref[j] = [_STIFF_STEPS * self.h, 1.0]
                    m.jnt_solimp[j][:3] = _STIFF_SOLIMP
        self.m, self.d = m, mujoco.MjData(m)
        self.torso = m.body(self._root_name(text)).id
        self.act_joints = [m.joint(n).id for n in names]
        self.act_q = [int(m.jnt_qposadr[j]) for j in self.act_joints]
        self.act_v = [int(m.jnt_dofadr[j]) for j in self.act_joints]
        armature = float(physics["actuator_armature"])
        for v in self.act_v:
            m.dof_armature[v] = armature
        state0 = self.rust.state()
        movable = state0["joint_names"]
        passive = [n for n in movable if n not in names]
        self.pas_q = [int(m.jnt_qposadr[m.joint(n).id]) for n in passive]
        self.pas_v = [int(m.jnt_dofadr[m.joint(n).id]) for n in passive]
        self.all_q = [int(m.jnt_qposadr[m.joint(n).id]) for n in movable]
        self.all_v = [int(m.jnt_dofadr[m.joint(n).id]) for n in movable]
        self.feet = [m.body(n).id for n in self.cfg["foot_links"]]
        self.effort = np.asarray(self.rust.effort_limits, dtype=np.float64)
        self.scale = np.asarray(self.rust.obs_scale, dtype=np.float64)
        self.standing_height = float(state0["standing_height"])
        self.weight = float(state0["weight"])
        stand = self.cfg["standing_pose"]
        ranges = [m.jnt_range[j] if m.jnt_limited[j] else (-np.inf, np.inf)
                  for j in self.act_joints]
        self.lo = np.array([r[0] for r in ranges])
        self.hi = np.array([r[1] for r in ranges])
        self.q_stand = np.clip([float(stand.get(n, 0.0)) for n in names], self.lo, self.hi)
        self.clock = self.cfg.get("gait_clock")
        self.max_steps = int(round(float(self.cfg["episode_seconds"]) / self.ts))
        self.track = float(self.cfg["track_length"])
        self.fall = self.cfg["fall"]
        self.target = self.cfg["target"]
        # Per actuated joint, the span of its targets around standing (None: to the limits).
        per_joint = self.target.get("joint_range") or {}
        spans = [per_joint.get(n, self.target.get("range")) for n in names]
        self.span_set = np.array([s is not None for s in spans])
        self.span = np.array([float(s) if s is not None else 0.0 for s in spans])
        self.mode = self.cfg["action"]

    @staticmethod
    def _root_name(text: str) -> str:
        root = ET.fromstring(text)
        children = {j.find("child").get("link") for j in root.findall("joint")}
        return [l.get("name") for l in root.findall("link") if l.get("name") not in children][0]

    # --- state and observation ------------------------------------------------------
    def _torso(self):
        """World pose (position, 3×3 rotation) and world linear and angular velocity of the
        torso link origin."""
        mj, m, d = self.mujoco, self.m, self.d
        pos = d.xpos[self.torso].copy()
        rot = d.xmat[self.torso].reshape(3, 3).copy()
        vel = np.zeros(6)
        mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_BODY, self.torso, vel, 0)
        return pos, rot, vel[3:].copy(), vel[:3].copy()

    def foot_forces(self) -> np.ndarray:
        """The ground's normal force on each foot, N."""
        mj, m, d = self.mujoco, self.m, self.d
        out = np.zeros(2)
        f = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            bodies = (m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2])
            for k, foot in enumerate(self.feet):
                if foot in bodies:
                    mj.mj_contactForce(m, d, i, f)
                    out[k] += abs(f[0])
        return out

    def phase(self) -> float:
        if not self.clock:
            return 0.0
        return (self.phase0 + self.steps * self.ts / float(self.clock["period"])) % 1.0

    def observation(self) -> np.ndarray:
        d = self.d
        pos, rot, v, w = self._torso()
        quat_wxyz = d.xquat[self.torso]
        quat = [quat_wxyz[1], quat_wxyz[2], quat_wxyz[3], quat_wxyz[0]]
        inv = rot.T
        obs: List[float] = [pos[2] - self.standing_height, pos[1], *quat]
        obs += list(inv @ v) + list(inv @ w) + list(inv @ self.acceleration)
        obs += [d.qpos[a] for a in self.act_q] + [d.qvel[a] for a in self.act_v]
        obs += [d.qpos[a] for a in self.pas_q] + [d.qvel[a] for a in self.pas_v]
        obs += list(self.foot_forces() / self.weight)
        obs += list(self.prev_action)
        if self.clock:
            a = 2 * math.pi * self.phase()
            obs += [math.sin(a), math.cos(a)]
        return (np.asarray(obs) * self.scale).astype(np.float32)

    # --- reset and step -------------------------------------------------------------
    def reset(self, seed: int) -> np.ndarray:
        """The Rust environment's initial state for ``seed``, copied into MuJoCo; returns the
        first observation."""
        mj = self.mujoco
        self.rust.reset(int(seed))
        s = self.rust.state()
        mj.mj_resetData(self.m, self.d)
        d = self.d
        x, y, z, w = s["base_quat"]
        d.qpos[0:3] = s["base_position"]
        d.qpos[3:7] = [w, x, y, z]
        d.qvel[0:3] = s["base_velocity"]
        d.qvel[3:6] = _quat_to_mat(s["base_quat"]).T @ np.asarray(s["base_angular_velocity"])
        for a, q in zip(self.all_q, s["q"]):
            d.qpos[a] = q
        for a, qd in zip(self.all_v, s["qd"]):
            d.qvel[a] = qd
        mj.mj_forward(self.m, d)
        self.phase0 = float(s["phase"])
        self.steps = 0
        self.prev_action = np.zeros(len(self.act_q))
        self.acceleration = np.zeros(3)
        self.prev_velocity = self._torso()[2]
        return self.observation()

    def _targets(self, action: np.ndarray) -> np.ndarray:
        """Joint-angle targets as esrl's ``WalkEnv::target_angle``: ``q_stand + a·span``
        clamped to the limits where a span is set (``target.joint_range``, else
        ``target.range``), else the limits at ±1."""
        residual, span = self.span_set, self.span
        to_limits = np.where(action >= 0, self.q_stand + action * (self.hi - self.q_stand),
                             self.q_stand + action * (self.q_stand - self.lo))
        return np.where(residual, np.clip(self.q_stand + action * span, self.lo, self.hi),
                        to_limits)

    def step(self, action: Sequence[float]):
        mj, m, d = self.mujoco, self.m, self.d
        a = np.nan_to_num(np.asarray(action, dtype=np.float64), nan=0.0).clip(-1.0, 1.0)
        self.prev_action = a
        torque = np.zeros(len(a))
        power = np.zeros(len(a))
        targets = self._targets(a) if self.mode == "target" else None
        kp, kd = float(self.target["stiffness"]), float(self.target["damping"])
        if self.servo == "actuator":
            d.ctrl[:] = targets
        for _ in range(self.substeps):
            q = np.array([d.qpos[i] for i in self.act_q])
            if self.servo == "explicit":
                if targets is not None:
                    qd = np.array([d.qvel[i] for i in self.act_v])
                    tau = np.clip(kp * (targets - q) - kd * qd, -self.effort, self.effort)
                else:
                    tau = a * self.effort
                d.qfrc_applied[:] = 0.0
                for v, t in zip(self.act_v, tau):
                    d.qfrc_applied[v] = t
            mj.mj_step(m, d)
            if self.servo == "actuator":
                tau = d.actuator_force.copy()
            q1 = np.array([d.qpos[i] for i in self.act_q])
            torque += tau / self.substeps
            power += np.abs(tau * (q1 - q) / self.h) / self.substeps
        self.steps += 1
        pos, rot, v, _ = self._torso()
        self.acceleration = (v - self.prev_velocity) / self.ts
        self.prev_velocity = v
        obs = self.observation()
        tilt = math.acos(max(-1.0, min(1.0, rot[2, 2])))
        fell = (pos[2] - self.standing_height < -float(self.fall["max_height_drop"])
                or tilt > float(self.fall["max_tilt"]) or not np.isfinite(obs).all())
        success = not fell and pos[0] >= self.track
        end = bool(self.cfg["end_at_finish"])
        terminated = fell or (success and end)
        truncated = not terminated and self.steps >= self.max_steps
        sample = {
            "time": self.steps * self.ts, "torso_x": pos[0], "torso_y": pos[1],
            "torso_z_error": pos[2] - self.standing_height, "forward_velocity": v[0],
            "torques": torque, "powers": power, "foot_forces": self.foot_forces(),
            "joint_angles": np.array([d.qpos[i] for i in self.act_q]),
            "foot_positions": [list(d.xpos[f][:2]) for f in self.feet],
            "torso_pitch": math.atan2(rot[0, 2], rot[2, 2]),
            "fell": fell, "success": success,
        }
        return obs, terminated, truncated, sample

    def episode(self, policy: Any, seed: int) -> Dict[str, Any]:
        """One deterministic episode of ``policy`` (an ``esrl_rs.Policy``) from ``seed``:
        the gait trace, ready for :func:`esrl_rs.metrics.gait_metrics`."""
        obs = self.reset(seed)
        policy.reset()
        names = list(self.rust.action_names)
        tr: Dict[str, Any] = {k: [] for k in ("time", "torso_x", "torso_y", "torso_z_error",
                                             "forward_velocity", "torques", "powers",
                                             "foot_forces", "joint_angles", "foot_positions",
                                             "torso_pitch")}
        fell, success_time = False, None
        while True:
            obs, terminated, truncated, s = self.step(policy.act(obs))
            for k in tr:
                tr[k].append(np.asarray(s[k], dtype=np.float64).tolist())
            fell = fell or s["fell"]
            if s["success"] and success_time is None:
                success_time = s["time"]
            if terminated or truncated:
                break
        limits = [[float(lo), float(hi)] if np.isfinite(lo) else None
                  for lo, hi in zip(self.lo, self.hi)]
        return {**tr, "actuator_names": names, "foot_names": list(self.cfg["foot_links"]),
                "fell": fell, "success_time": success_time, "joint_limits": limits}


def _past_limit_deg(angles: Any, limits: Sequence[Any]) -> float:
    """The largest angle (degrees, ≥ 0) by which any joint of ``angles`` (steps × joints,
    radians) went past its ``limits`` (``[lower, upper]`` per joint, ``None`` if unlimited)."""
    q = np.asarray(angles, dtype=np.float64).reshape(len(angles), -1)
    worst = 0.0
    for k, lim in enumerate(limits):
        if lim is None or len(q) == 0:
            continue
        lo, hi = float(lim[0]), float(lim[1])
        worst = max(worst, float(np.max(np.maximum(lo - q[:, k], q[:, k] - hi))))
    return math.degrees(worst)


def _summary(gaits: List[Dict[str, Any]], past_limit: Sequence[float]) -> Dict[str, Any]:
    classes: Dict[str, int] = {}
    for g in gaits:
        c = (g.get("cycle") or {}).get("gait_class", "fall")
        classes[c] = classes.get(c, 0) + 1
    times = [g["track_time"] for g in gaits if g.get("track_time") is not None]
    pitches = [g["torso_pitch"]["mean"] for g in gaits if g.get("torso_pitch")]
    return {
        "episodes": len(gaits),
        "finished": len(times),
        "falls": sum(bool(g["fell"]) for g in gaits),
        "classes": dict(sorted(classes.items(), key=lambda kv: -kv[1])),
        "track_time": float(np.mean(times)) if times else None,
        "speed": float(np.mean([g["mean_forward_velocity"] for g in gaits])),
        "sway": float(np.mean([g["mean_abs_lateral"] for g in gaits])),
        "knee_asymmetry": float(np.mean([g["knee_torque_asymmetry"] for g in gaits])),
        # The torso's mean lean from the vertical, forward positive (degrees).
        "torso_pitch_deg": (math.degrees(float(np.mean(pitches))) if pitches else None),
        # How far the joints went past the URDF's limits (module docs: ``limits``).
        "past_limit_deg": max(past_limit, default=0.0),
    }


def cross_check(path: str, episodes: int = 10, seed: int = 0, cone: str = "pyramidal",
                servo: str = "explicit", last: bool = False,
                limits: str = "soft", default_starts: bool = False) -> Dict[str, Any]:
    """The policy in ``path`` (a run folder's kept policy, or with ``last`` its newest
    checkpoint, as ``esrl eval``; a checkpoint, ``best/`` or record ``policy/`` folder)
    from reset seeds ``seed … seed + episodes − 1`` in esrl (``Policy.evaluate``, the code
    of ``esrl eval``) and on MuJoCo (:class:`MujocoWalk` with ``cone`` and ``servo``): both
    engines' gait metrics (:func:`esrl_rs.metrics.gait_metrics`), summarised per engine and
    per episode. ``limits``: MuJoCo's joint limits (:data:`LIMITS`). ``default_starts``:
    both engines from the task's standard starts (``esrl eval --default-starts``), for a
    policy trained from other starts."""
    return cross_checks(path, episodes, seed, [(cone, servo, limits)], last, default_starts)[0]


def cross_checks(path: str, episodes: int, seed: int,
                 settings: Sequence[Sequence[str]], last: bool = False,
                 default_starts: bool = False) -> List[Dict[str, Any]]:
    """:func:`cross_check` under each ``(cone, servo)`` or ``(cone, servo, limits)`` of
    ``settings``, esrl's episodes run once."""
    from .policy import load_policy

    # Both engines run the plain task: a policy trained under disturbances ([walk.perturb])
    # is cross-checked without them, as `esrl eval --undisturbed` evaluates it.
    policy = load_policy(path, undisturbed=True, last=last, default_starts=default_starts)
    if policy.env != "walk":
        raise ValueError(f"{path}: a {policy.env} run; sim2sim is for the walking task")
    walk = policy._core.walk_config
    evaluated = policy.evaluate(episodes, seed)["episodes"]
    gaits = [e["gait"] for e in evaluated]
    ours = [g for g in gaits if g is not None]
    ours_past = [_past_limit_deg(e["trace"]["joint_angle"], e["trace"]["joint_limits"])
                 for e in evaluated if e.get("trace") is not None]

    def cls(g: Optional[Dict[str, Any]]) -> Optional[str]:
        return (g.get("cycle") or {}).get("gait_class") if g is not None else "fall"

    out = []
    done = set()
    for cone, servo, *rest in settings:
        limits = rest[0] if rest else "soft"
        env = MujocoWalk(walk, cone=cone, servo=servo, limits=limits)
        # A torque policy has no servo: every servo setting runs the same episodes.
        if (cone, env.servo, limits) in done:
            continue
        done.add((cone, env.servo, limits))
        track = float(env.track)
        mj, mj_past = [], []
        for k in range(episodes):
            t = env.episode(policy, seed + k)
            mj.append(metrics.gait_metrics(t, track_length=track))
            mj_past.append(_past_limit_deg(t["joint_angles"], t["joint_limits"]))
        out.append({
            "policy": os.fspath(path), "checkpoint": policy.checkpoint, "seed": seed,
            "episodes": episodes, "default_starts": default_starts,
            "mujoco_settings": {"cone": cone, "servo": env.servo, "action": env.mode,
                                "limits": limits},
            "esrl": _summary(ours, ours_past), "mujoco": _summary(mj, mj_past),
            "per_episode": [{
                "seed": seed + k, "esrl": cls(g), "mujoco": cls(m),
                "esrl_finished": g is not None and g.get("track_time") is not None,
                "mujoco_finished": m.get("track_time") is not None,
                "mujoco_distance": m["distance"]} for k, (g, m) in enumerate(zip(gaits, mj))]})
    return out


def _row(name: str, s: Dict[str, Any]) -> str:
    classes = ", ".join(f"{c} {n}" for c, n in s["classes"].items())
    tt = f"{s['track_time']:.1f}" if s["track_time"] is not None else "–"
    pitch = f"{s['torso_pitch_deg']:.1f}" if s.get("torso_pitch_deg") is not None else "–"
    return (f"| {name} | {classes} | {s['finished']}/{s['episodes']} | {s['falls']} | "
            f"{tt} | {s['speed']:.2f} | {s['sway']:.3f} | {100 * s['knee_asymmetry']:.1f} % | "
            f"{pitch} | {s['past_limit_deg']:.1f} |")


_HEADER = ("| engine | gait classes | finished 50 m | falls | track time (s) | speed (m/s) | "
           "sway (m) | knee asym. | torso pitch (°) | past a limit (°) |\n"
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")


def _table(r: Dict[str, Any]) -> str:
    stiff = r["mujoco_settings"].get("limits", "soft") == "stiff"
    name = "MuJoCo, stiff limits" if stiff else "MuJoCo"
    return "\n".join([_HEADER, _row("esrl (Rapier)", r["esrl"]), _row(name, r["mujoco"])]) + "\n"


def _tables(results: Sequence[Dict[str, Any]]) -> str:
    """One table per policy: esrl's row, then MuJoCo's under each setting."""
    parts = []
    for k, r in enumerate(results):
        if k == 0 or r["policy"] != results[k - 1]["policy"]:
            if parts:
                parts.append("")
            standard = ", the task's standard starts" if r.get("default_starts") else ""
            parts += [f"{r['policy']} ({r['episodes']} starts from reset seed {r['seed']}"
                      f"{standard})", "",
                      _HEADER, _row("esrl (Rapier)", r["esrl"])]
        st = r["mujoco_settings"]
        how = f"{st['servo']} servo" if st.get("action", "target") == "target" else "torques"
        if st.get("limits", "soft") == "stiff":
            how += ", stiff limits"
        parts.append(_row(f"MuJoCo, {st['cone']} cone, {how}", r["mujoco"]))
    return "\n".join(parts) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m esrl_rs.sim2sim",
                                 description="Run an esrl walking policy in esrl and on MuJoCo "
                                 "from the same starts and compare the gait metrics.")
    ap.add_argument("policy", nargs="+", help="a run folder (its kept policy, as esrl eval), a "
                    "checkpoint or best/ folder, or a record's policy/ folder (several: one "
                    "table each)")
    ap.add_argument("--last", action="store_true",
                    help="a run folder's newest checkpoint instead of its kept policy")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0, help="reset seed of the first episode")
    ap.add_argument("--cone", choices=CONES + ("all",), default="pyramidal",
                    help="MuJoCo's friction cone (default pyramidal, MuJoCo's own; elliptic is "
                    "the shape of Rapier's; all: both)")
    ap.add_argument("--servo", choices=SERVOS + ("all",), default="explicit",
                    help="the joint-angle servo as a torque computed at each physics step "
                    "(explicit, the default) or as MuJoCo position actuators (actuator; all: "
                    "both)")
    ap.add_argument("--limits", choices=LIMITS + ("all",), default="soft",
                    help="MuJoCo's joint limits: soft (the default, MuJoCo's own: torque can "
                    "push a joint far past its limit), stiff (the stiffest MuJoCo allows: a few "
                    "degrees past, as esrl's own limits) or all: both")
    ap.add_argument("--default-starts", action="store_true",
                    help="from the task's standard starts (walk.init_noise and walk.reset at "
                    "their defaults, as esrl eval --default-starts), for a policy trained from "
                    "other starts")
    ap.add_argument("--json", action="store_true", help="print the result as JSON")
    a = ap.parse_args(argv)
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print('error: MuJoCo is not installed: pip install "esrl_rs[mujoco]" (or pip install '
              "mujoco)", file=sys.stderr)
        return 1
    if a.episodes < 1:
        print("error: --episodes must be at least 1", file=sys.stderr)
        return 2
    cones = CONES if a.cone == "all" else (a.cone,)
    servos = SERVOS if a.servo == "all" else (a.servo,)
    limits = LIMITS if a.limits == "all" else (a.limits,)
    settings = [(c, s, lim) for lim in limits for c in cones for s in servos]
    results: List[Dict[str, Any]] = []
    try:
        for p in a.policy:
            results += cross_checks(p, a.episodes, a.seed, settings, a.last, a.default_starts)
    except (ValueError, OSError, _native.EsrlError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if len(results) == 1:
        print(json.dumps(results[0], indent=1) if a.json else _table(results[0]), end="")
    else:
        print(json.dumps(results, indent=1) if a.json else _tables(results), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
