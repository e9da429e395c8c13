"""The model-based baseline (a reading of docs/equations.md where the paper is
silent): the robot's LHS controller with a constant chi (task.gains.chi_model_based) and the static
inversion u = B0^-1 (tau_c^r + D0 qdot); no integrator, no learning."""
from pydrake.systems.primitives import ConstantVectorSource

from dacph_drake.controllers.closed_loop import (AddLhsSide, ClosedLoop, ControllerBuilder,
                                     assemble_closed_loop)
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.systems.model_based_inverter import ModelBasedInverter


def build_model_based_diagram(*scenarios: Scenario) -> ClosedLoop:
    """Builds the model-based baseline loop "model_based" of the scenarios' robot: the
    LHS's request is inverted through the nominal RHS (B0, D0); on a nominal ground
    truth the inversion is exact and the plant receives the request.

    Args:
        *scenarios: One scenario, or a batch of trials for one diagram."""
    def add(loop: ClosedLoop, controller: ControllerBuilder):
        lhs, systems = AddLhsSide(loop, controller, Excitation(amplitude=0.0),
                                  identify=False)
        builder = controller.builder
        fixed_chi = builder.AddNamedSystem("fixed_chi", ConstantVectorSource(
            [s.task.gains.chi_model_based for s in loop.scenarios]))
        builder.Connect(fixed_chi.get_output_port(), lhs.GetInputPort("chi"))
        inverter = builder.AddNamedSystem("model_based_inverter", ModelBasedInverter(
            uncertainties=[s.uncertainty for s in loop.scenarios]))
        builder.Connect(lhs.GetOutputPort("tau_request"),
                        inverter.GetInputPort("tau_request"))
        controller.Input(inverter.GetInputPort("qdot"), "qdot")
        builder.ExportOutput(inverter.GetOutputPort("u"), "u")
        return {**systems, "model_based_inverter": inverter}
    return assemble_closed_loop(scenarios[0], "model_based", add, scenarios[1:])
