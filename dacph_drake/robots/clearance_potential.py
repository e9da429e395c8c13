"""The null-space potential of a spatial arm: keeps every link off the base, from
SceneGraph's signed distances between the description's collision geometries
(the planar arms' potential.BaseRepulsionPotential measures link outlines in closed
form instead).

    U(q) = gain / 2 sum_k max(0, margin - phi_k(q))^2,
    grad U = -gain sum_k max(0, margin - phi_k) grad phi_k,
    grad phi_k = (J_bar_A(p_A) - J_bar_B(p_B))_v^T nhat_BA,

phi_k the signed distance between link k and the base, p_A, p_B its witness points
on the link and on the base, nhat_BA the unit normal from the base towards the link,
J_bar the translational rows of the generalized Jacobians (the base moves too: zero
momentum). The links joined by a joint to the base, or to a body welded to it (an
arm's root mounted on it, scenario.ArmBase), are not measured against it: their
joint sits on its surface (Drake filters the first kind itself)."""
from dataclasses import dataclass
from typing import Optional

import numpy as np
from pydrake.geometry import (Box, Capsule, CollisionFilterDeclaration, Convex,
                              Cylinder, Ellipsoid, GeometrySet, Mesh, Sphere)
from pydrake.multibody.tree import BodyIndex

from dacph_drake.robots.description import ParsedDescription
from dacph_drake.dynamics.floating_model import FloatingBaseModel


@dataclass
class Clearance:
    """The potential's value at a configuration (BaseClearancePotential.Evaluate).

    Attributes:
        U: The potential [J-like units of gain * m^2].
        gradient: dU/dq (n).
        min_distance: The smallest link-base signed distance [m] (inf beyond the
            query distance).
    """
    U: float                # [J-like units of gain * m^2]
    gradient: np.ndarray    # dU/dq
    min_distance: float     # smallest link-base signed distance [m] (inf beyond query)


class BaseClearancePotential:
    """U(q) at a base pose (module docstring).

    Args:
        parsed: The robot (description.ParsedDescription: the plant and SceneGraph
            the ground truth runs on, queried in contexts of its own with the
            collision geometry).
        model: The controller's model of the same description (the same body
            indices), which gives the Jacobians.
        gain: The potential's gain.
        margin: The distance below which a link-base pair is repelled [m].
        query_distance: How far Evaluate looks for the nearest distance by default
            [m] (at least ``margin``).
    """

    def __init__(self, *, parsed: ParsedDescription, model: FloatingBaseModel,
                 gain: float, margin: float, query_distance: float = 1.0):
        self._parsed, self._plant = parsed, parsed.plant
        self._plant_context, self._scene_graph_context = parsed.ClearanceContexts()
        _FilterLinksOnTheBase(self._plant, parsed.scene_graph, self._scene_graph_context)
        self._query = parsed.scene_graph.get_query_output_port()
        self._inspector = parsed.scene_graph.model_inspector()
        self._model, self._gain, self.margin = model, gain, margin
        self._query_distance = max(query_distance, margin)
        base = self._plant.get_body(next(iter(self._plant.GetFloatingBaseBodies())))
        self._base_geometries = set(self._plant.GetCollisionGeometriesForBody(base))
        self._reach = _JointReach(model.tree, [
            _BodyRadius(self._plant, self._inspector, body) for body in model.tree.bodies])
        # The last query's q and a lower bound of every link-base distance there,
        # exactly the nearest one when the query found a link-base pair.
        self._known_q, self._known_distance, self._known_exact = None, -np.inf, False

    def _Beyond(self, q, distance: float) -> bool:
        """Whether every link-base distance at q is certainly above ``distance``:
        the distances are functions of q alone (the base pose moves links and base
        together), each within sum_j reach_j |dq_j| of its value at the last
        query's q (_JointReach), so above known - reach . |q - q_known|."""
        return (self._known_q is not None and self._known_distance
                - self._reach @ np.abs(q - self._known_q) > distance)

    def _NearestAtMost(self, q) -> float:
        """An upper bound of the nearest link-base distance at q: the last query's
        nearest plus reach . |q - q_known| (inf when that query found no pair)."""
        if self._known_q is None or not self._known_exact:
            return np.inf
        return self._known_distance + self._reach @ np.abs(q - self._known_q)

    def _BodyFrame(self, geometry):
        """The model plant's frame of the body owning ``geometry`` and the
        geometry's pose in that body."""
        body = self._plant.GetBodyFromFrameId(self._inspector.GetFrameId(geometry))
        return (self._model.plant.get_body(body.index()).body_frame(),
                self._inspector.GetPoseInFrame(geometry))

    def Evaluate(self, q: np.ndarray, base_pose: np.ndarray,
                 query_distance: Optional[float] = None) -> Clearance:
        """U, its gradient and the nearest link-base distance at a configuration.

        The model is evaluated at q only when a pair is within the margin (the
        witness points' Jacobians). Where every link is certainly beyond the query
        distance (_Beyond), the query is not made: its answer would be U = 0, a zero
        gradient and inf. The query looks no further than the margin or the nearest
        distance's upper bound (_NearestAtMost), whichever is larger: beyond it are
        neither pairs within the margin nor the nearest one. A query made looks
        CERTIFY further than that, so that the next calls can be answered from it.

        Args:
            q: The joint angles (n) [rad].
            base_pose: The base's pose (qw, qx, qy, qz, x, y, z), the base joint's
                coordinates.
            query_distance: The distance beyond which the nearest distance is
                reported as inf [m] (None: the one it was made with; U needs the
                margin only).

        Returns:
            The Clearance."""
        query_distance = (self._query_distance if query_distance is None
                          else max(query_distance, self.margin))
        q = np.asarray(q, float)
        gradient = np.zeros(self._model.num_joints)
        if self._Beyond(q, query_distance):
            return Clearance(U=0.0, gradient=gradient, min_distance=np.inf)
        query_distance = max(self.margin, min(query_distance, self._NearestAtMost(q)))
        self._plant.SetPositions(self._plant_context,
                                 self._model.FullPositions(q, base_pose))
        self._parsed.UpdatePoses(self._plant_context, self._scene_graph_context)
        query = self._query.Eval(self._scene_graph_context)
        looked = query_distance + CERTIFY
        pairs = query.ComputeSignedDistancePairwiseClosestPoints(looked)
        U, nearest, known, exact, evaluation = 0.0, np.inf, looked, False, None
        for pair in pairs:
            if (pair.id_A in self._base_geometries) == (pair.id_B in self._base_geometries):
                continue                                   # not a link-base pair
            known, exact = min(known, pair.distance), True
            if pair.distance > query_distance:
                continue                                   # beyond what was asked
            link, base = (pair.id_A, pair.id_B) if pair.id_B in self._base_geometries \
                else (pair.id_B, pair.id_A)
            sign = 1.0 if link == pair.id_A else -1.0      # nhat points base -> link
            nhat = sign * pair.nhat_BA_W
            p_link, p_base = ((pair.p_ACa, pair.p_BCb) if link == pair.id_A
                              else (pair.p_BCb, pair.p_ACa))
            nearest = min(nearest, pair.distance)
            depth = self.margin - pair.distance
            if depth <= 0:
                continue
            if evaluation is None:
                evaluation = self._model.Evaluate(q, derivatives=False)
            J = []
            for geometry, p_G in ((link, p_link), (base, p_base)):
                frame, X_BG = self._BodyFrame(geometry)
                J.append(self._model.GeneralizedJacobian(
                    q, frame, X_BG.multiply(p_G), base_positions=base_pose,
                    evaluation=evaluation)[3:])
            U += 0.5 * self._gain * depth**2
            gradient -= self._gain * depth * (J[0] - J[1]).T @ nhat
        self._known_q, self._known_distance, self._known_exact = q.copy(), known, exact
        return Clearance(U=U, gradient=gradient, min_distance=nearest)


# [m] a query looks this far beyond the distance asked, so that a link moving
# away from the margin is known to be beyond it for a while without a query.
CERTIFY = 0.2

# The radius of a shape's smallest ball about its frame's origin.
_SHAPE_RADIUS = {
    Sphere: lambda shape: shape.radius(),
    Box: lambda shape: 0.5 * np.linalg.norm(shape.size()),
    Cylinder: lambda shape: np.hypot(shape.radius(), 0.5 * shape.length()),
    Capsule: lambda shape: shape.radius() + 0.5 * shape.length(),
    Ellipsoid: lambda shape: max(shape.a(), shape.b(), shape.c()),
    Convex: lambda shape: _HullRadius(shape.GetConvexHull()),
    Mesh: lambda shape: _HullRadius(shape.GetConvexHull()),
}


def _HullRadius(hull) -> float:
    return max(np.linalg.norm(hull.vertex(i)) for i in range(hull.num_vertices()))


def _BodyRadius(plant, inspector, body) -> float:
    """The radius about ``body``'s origin of a ball holding its collision
    geometries (-inf without any; inf for a shape without a bound, a half space)."""
    radius = -np.inf
    for geometry in plant.GetCollisionGeometriesForBody(
            plant.get_body(body.index())):
        shape = inspector.GetShape(geometry)
        bound = _SHAPE_RADIUS.get(type(shape), lambda shape: np.inf)(shape)
        radius = max(radius, np.linalg.norm(inspector.GetPoseInFrame(geometry)
                                            .translation()) + bound)
    return radius


def _JointReach(tree, radius) -> np.ndarray:
    """reach_j: the largest distance of a collision geometry's point moved by joint
    j from j's axis, bounded by the fixed offsets along the chain, so that
    |d phi / d q_j| <= reach_j for every link-base distance phi (a revolute
    joint moves a point at r from its axis at r per rad; kinematic_tree's
    X_WC = X_WP X_PF Rot X_MC: the chain from joint j's origin to node k is the
    offsets t(X_MC) of j's node, then t(X_PF) + t(X_MC) of each node after it,
    each a fixed length, and ``radius``[k] holds node k's geometry about its
    origin)."""
    offset_in = np.linalg.norm(tree.X_PF[:, :3, 3], axis=1)
    offset_out = np.linalg.norm(tree.X_MC[:, :3, 3], axis=1)
    reach = np.zeros(len(tree.joint_node))
    for j, start in enumerate(tree.joint_node):
        chain = np.full(len(tree.bodies), np.nan)
        chain[start] = offset_out[start]
        for node in range(start + 1, len(tree.bodies)):
            if tree.below[j, node]:
                chain[node] = chain[tree.parent[node]] + offset_in[node] + offset_out[node]
        moved = tree.below[j] & (np.asarray(radius) > -np.inf)
        reach[j] = max([0.0] + list(chain[moved] + np.asarray(radius)[moved]))
    return reach


def _FilterLinksOnTheBase(plant, scene_graph, context) -> None:
    """Excludes, in the SceneGraph ``context``, the collision pairs of the base with
    each body whose joint's parent is welded to the base (the bodies Drake leaves
    unfiltered when the arm's root is a body of its own, welded to the base), and
    every pair of two links: the potential measures links against the base only,
    and a query then computes those pairs alone."""
    base = plant.get_body(next(iter(plant.GetFloatingBaseBodies())))
    welded = {body.index() for body in plant.GetBodiesWeldedTo(base)}
    on_base = [plant.get_joint(j).child_body() for j in plant.GetJointIndices()
               if plant.get_joint(j).parent_body().index() in welded
               and plant.get_joint(j).child_body().index() not in welded]
    geometries = [g for body in on_base for g in plant.GetCollisionGeometriesForBody(body)]
    manager = scene_graph.collision_filter_manager(context)
    if geometries:
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(
            GeometrySet(plant.GetCollisionGeometriesForBody(base)),
            GeometrySet(geometries)))
    links = [g for index in range(plant.num_bodies()) if index != int(base.index())
             for g in plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(index)))]
    manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(links)))
