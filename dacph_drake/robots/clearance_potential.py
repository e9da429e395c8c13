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

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

from dacph_drake.robots.description import ParsedDescription
from dacph_drake.dynamics.floating_model import FloatingBaseModel


@dataclass
class Clearance:
    U: float                # [J-like units of gain * m^2]
    gradient: np.ndarray    # dU/dq
    min_distance: float     # smallest link-base signed distance [m] (inf beyond query)


class BaseClearancePotential:
    """U(q) at a base pose for the robot ``parsed`` (description.ParsedDescription:
    the plant and SceneGraph the ground truth runs on, queried in contexts of its
    own with the collision geometry; module docstring), its Jacobians from ``model``
    (the controller's model of the same description: the same body indices)."""

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

    def _BodyFrame(self, geometry):
        """The model plant's frame of the body owning ``geometry`` and the
        geometry's pose in that body."""
        body = self._plant.GetBodyFromFrameId(self._inspector.GetFrameId(geometry))
        return (self._model.plant.get_body(body.index()).body_frame(),
                self._inspector.GetPoseInFrame(geometry))

    def Evaluate(self, q, base_pose, evaluation=None, query_distance=None
                 ) -> Clearance:
        """U, its gradient and the nearest distance (inf beyond ``query_distance``,
        default the one it was made with; U needs the margin only) at joints q and
        the base pose (``evaluation``: the model's Evaluate(q), when the caller has
        it)."""
        self._plant.SetPositions(self._plant_context,
                                 self._model.FullPositions(q, base_pose))
        self._parsed.UpdatePoses(self._plant_context, self._scene_graph_context)
        query = self._query.Eval(self._scene_graph_context)
        pairs = query.ComputeSignedDistancePairwiseClosestPoints(
            self._query_distance if query_distance is None
            else max(query_distance, self.margin))
        U, gradient, nearest = 0.0, np.zeros(self._model.num_joints), np.inf
        for pair in pairs:
            if (pair.id_A in self._base_geometries) == (pair.id_B in self._base_geometries):
                continue                                   # not a link-base pair
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
            J = []
            for geometry, p_G in ((link, p_link), (base, p_base)):
                frame, X_BG = self._BodyFrame(geometry)
                J.append(self._model.GeneralizedJacobian(
                    q, frame, X_BG.multiply(p_G), base_positions=base_pose,
                    evaluation=evaluation)[3:])
            U += 0.5 * self._gain * depth**2
            gradient -= self._gain * depth * (J[0] - J[1]).T @ nhat
        return Clearance(U=U, gradient=gradient, min_distance=nearest)


def _FilterLinksOnTheBase(plant, scene_graph, context) -> None:
    """Excludes the collision pairs of the base with each body whose joint's parent
    is welded to the base (the bodies Drake leaves unfiltered when the arm's root is
    a body of its own, welded to the base), in the SceneGraph ``context``."""
    base = plant.get_body(next(iter(plant.GetFloatingBaseBodies())))
    welded = {body.index() for body in plant.GetBodiesWeldedTo(base)}
    on_base = [plant.get_joint(j).child_body() for j in plant.GetJointIndices()
               if plant.get_joint(j).parent_body().index() in welded
               and plant.get_joint(j).child_body().index() not in welded]
    geometries = [g for body in on_base for g in plant.GetCollisionGeometriesForBody(body)]
    if geometries:
        scene_graph.collision_filter_manager(context).Apply(
            CollisionFilterDeclaration().ExcludeBetween(
                GeometrySet(plant.GetCollisionGeometriesForBody(base)),
                GeometrySet(geometries)))
