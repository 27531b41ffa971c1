"""Bad and degenerate input to the association stages (gates, formation, assignment, mixture
reduction, N-scan): a ConfigError or ModelError naming where, never a raw numpy exception or a
silently wrong mask or weight."""

import numpy as np
import pytest

from relloc.association.assignment import assign
from relloc.association.gating import GateSettings, mahalanobis_batch
from relloc.association.hypotheses import FormationSettings, formation_weights
from relloc.association.mixture_reduction import cap_mask
from relloc.association.nscan import family_keep_mask, new_history
from relloc.errors import ConfigError, ModelError


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("p_gate", "0.9"),
        ("p_gate", None),
        ("yaw_sigma_uniform", "1"),
        ("horizon", True),
    ],
)
def test_gate_settings_of_wrong_type_name_the_field(field, value):
    with pytest.raises(ConfigError, match=rf"GateSettings\.{field}"):
        GateSettings(**{field: value})


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("p_birth", "0.5"),
        ("p_detect", None),
        ("birth_variances", "abcd"),
        ("birth_variances", 5),
        ("birth_yaw_components", 2.5),
        ("birth_yaw_components", True),
    ],
)
def test_formation_settings_of_wrong_type_name_the_field(field, value):
    with pytest.raises(ConfigError, match=rf"FormationSettings\.{field}"):
        FormationSettings(**{field: value})


def test_formation_settings_take_an_array_of_birth_variances():
    s = FormationSettings(birth_variances=np.array([0.1, 0.1, 0.05, 4.0 * np.pi]))
    assert s.birth_variances == FormationSettings().birth_variances


@pytest.mark.parametrize("p_detect", [float("nan"), 2.0, -0.1])
def test_formation_weights_refuse_a_detection_probability_outside_0_1(p_detect):
    ones = np.ones((1, 1))
    with pytest.raises(ConfigError, match="p_detect"):
        formation_weights(
            np.ones(1), ones, ones.astype(bool), FormationSettings(), 1.0, p_detect=p_detect
        )


def test_a_singular_innovation_covariance_is_a_model_error():
    with pytest.raises(ModelError, match="mahalanobis_batch"):
        mahalanobis_batch(np.ones((1, 2)), np.zeros((1, 2, 2)))


def test_assignment_refuses_a_minus_infinite_cost():
    with pytest.raises(ModelError, match="−inf cost"):
        assign(np.array([[-np.inf, 1.0]]), np.array([1.0]))


@pytest.mark.parametrize("size", [float("nan"), 2.5, "3"])
def test_cap_mask_needs_an_integer_size(size):
    with pytest.raises(ModelError, match="max_components"):
        cap_mask(np.ones(3), size)


@pytest.mark.parametrize("depth", [float("nan"), 1.5])
def test_new_history_needs_an_integer_depth(depth):
    with pytest.raises(ModelError, match="depth"):
        new_history(np.arange(2), depth)


def test_family_keep_mask_needs_a_history_per_row():
    with pytest.raises(ModelError, match="history"):
        family_keep_mask(np.zeros(3, dtype=np.int64), np.ones(3), 0.1)
