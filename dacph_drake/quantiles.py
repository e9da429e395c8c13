"""Quantiles the learner's intervals and the model-error measurement share."""


def student_quantile(z: float, dof: float) -> float:
    """Student's t quantile at normal quantile z (Cornish-Fisher, third order).

    Args:
        z: The standard normal quantile.
        dof: The degrees of freedom, >= 2."""
    z3, z5, z7 = z ** 3, z ** 5, z ** 7
    return (z + (z3 + z) / (4 * dof) + (5 * z5 + 16 * z3 + 3 * z) / (96 * dof ** 2)
            + (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * dof ** 3))
