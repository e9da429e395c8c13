"""The model-based baseline (docs/equations.md; the paper is silent): the LHS controller
with a constant chi (task.gains.chi_model_based) and u = B0^-1 (tau_c^r + D0 qdot)."""
from pydrake.systems.primitives import ConstantVectorSource

from dacph_drake.controllers.closed_loop import (AddLhsSide, ClosedLoop, ControllerBuilder,
                                                 LhsRequest, assemble_closed_loop)
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.systems.model_based_inverter import ModelBasedInverter


def build_model_based_diagram(*scenarios: Scenario) -> ClosedLoop:
    """Builds the baseline loop "model_based" (module docstring).

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
        builder.Connect(LhsRequest(lhs, systems), inverter.GetInputPort("tau_request"))
        controller.Input(inverter.GetInputPort("qdot"), "qdot")
        builder.ExportOutput(inverter.GetOutputPort("u"), "u")
        return {**systems, "model_based_inverter": inverter}
    return assemble_closed_loop(scenarios[0], "model_based", add, scenarios[1:])
