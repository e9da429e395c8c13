"""The null-space potential of a spatial arm, keeping every link off the base, from
SceneGraph's signed distances between collision geometries:

    U(q) = gain / 2 sum_k max(0, margin - phi_k(q))^2,
    grad U = -gain sum_k max(0, margin - phi_k) grad phi_k,
    grad phi_k = (J_bar_A(p_A) - J_bar_B(p_B))_v^T nhat_BA,

phi_k link k's signed distance to the base, p_A, p_B its witness points, nhat_BA the
normal from base to link; links jointed to the base are not measured against it."""
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
        U: The potential [gain * m^2].
        gradient: dU/dq (n).
        min_distance: The smallest link-base signed distance [m] (inf beyond the query)."""
    U: float                # [J-like units of gain * m^2]
    gradient: np.ndarray    # dU/dq
    min_distance: float     # smallest link-base signed distance [m] (inf beyond query)


class BaseClearancePotential:
    """U(q) at a base pose (module docstring).

    Args:
        parsed: The robot's ParsedDescription, queried in contexts of its own.
        model: The controller's model of the same description, for the Jacobians.
        gain: The potential's gain.
        margin: The distance below which a link-base pair is repelled [m].
        query_distance: Evaluate's default query distance [m] (at least ``margin``)."""

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
        """Whether every link-base distance at q is certainly above ``distance``: each
        is within reach . |q - q_known| of the last query's (_JointReach)."""
        return (self._known_q is not None and self._known_distance
                - self._reach @ np.abs(q - self._known_q) > distance)

    def _NearestAtMost(self, q) -> float:
        """An upper bound of the nearest link-base distance at q (inf: unknown)."""
        if self._known_q is None or not self._known_exact:
            return np.inf
        return self._known_distance + self._reach @ np.abs(q - self._known_q)

    def _BodyFrame(self, geometry):
        """The model plant's frame of ``geometry``'s body, and its pose in that body."""
        body = self._plant.GetBodyFromFrameId(self._inspector.GetFrameId(geometry))
        return (self._model.plant.get_body(body.index()).body_frame(),
                self._inspector.GetPoseInFrame(geometry))

    def Evaluate(self, q: np.ndarray, base_pose: np.ndarray,
                 query_distance: Optional[float] = None) -> Clearance:
        """U, its gradient and the nearest link-base distance at q (a Clearance); no query
        where every link is certainly beyond the query distance (_Beyond), and a query looks
        CERTIFY further so that later calls can be answered from it.

        Args:
            q: The joint angles (n) [rad].
            base_pose: The base's pose (qw, qx, qy, qz, x, y, z).
            query_distance: Beyond it the nearest distance is inf [m] (None: default)."""
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
    """Radius about ``body``'s origin of its collision geometries (-inf: none)."""
    radius = -np.inf
    for geometry in plant.GetCollisionGeometriesForBody(
            plant.get_body(body.index())):
        shape = inspector.GetShape(geometry)
        bound = _SHAPE_RADIUS.get(type(shape), lambda shape: np.inf)(shape)
        radius = max(radius, np.linalg.norm(inspector.GetPoseInFrame(geometry)
                                            .translation()) + bound)
    return radius


def _JointReach(tree, radius) -> np.ndarray:
    """reach_j >= |d phi / d q_j| for every link-base distance phi, from the chain's fixed
    offsets and each node's geometry ``radius``."""
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
    """Filters the base's pairs with bodies jointed to a body welded to it, and every
    link-link pair: a query then computes link-base pairs alone."""
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
