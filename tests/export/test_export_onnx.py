"""policy.onnx (opset >= 17) run by onnxruntime equals SB3's predict(obs,
deterministic=True) within 1e-5 on >= 10,000 observations each committed policy meets in its
own task, and on small models of every exported algorithm."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")

import export_cases as cases
import onnx

from baselines.export import onnx as export_onnx
from baselines.export import verify
from baselines.export.build import ONNX


@pytest.mark.slow
@pytest.mark.parametrize("name", cases.MODELS)
def test_onnx_equals_predict_on_the_policys_own_observations(name):
    spec = f"sb3:{name}"
    features, net, _ = cases.reference(spec)
    assert len(features) >= cases.N_OBS
    got = verify.onnx_actions(cases.exported(spec) / ONNX, features)
    np.testing.assert_allclose(got, net, rtol=0, atol=cases.TOL)
    print(f"{name}: ONNX vs predict, max |diff| {np.abs(got - net).max():.2e} on {len(got)}")


@pytest.mark.parametrize("case", sorted(cases.TINY))
def test_onnx_of_every_algorithm_and_output_transform(case):
    spec = cases.tiny(case)
    lp = cases.loaded(spec)
    x = np.random.default_rng(1).uniform(-5, 5, (500, lp.network.input_size))
    want, _ = lp.policy.model.predict(x.astype(np.float32), deterministic=True)
    got = verify.onnx_actions(cases.exported(spec) / ONNX, x)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)


def test_the_graph_declares_opset_17_a_batch_axis_and_its_provenance():
    spec = "sb3:pair_quad3d"
    model = onnx.load(str(cases.exported(spec) / ONNX))
    assert [o.version for o in model.opset_import if o.domain in ("", "ai.onnx")] == [
        export_onnx.OPSET
    ]
    assert export_onnx.OPSET >= 17
    (inp,), (out,) = model.graph.input, model.graph.output
    assert inp.name == export_onnx.INPUT and out.name == export_onnx.OUTPUT
    dims = [d.dim_param or d.dim_value for d in inp.type.tensor_type.shape.dim]
    assert dims == ["batch", cases.loaded(spec).network.input_size]
    props = {p.key: p.value for p in model.metadata_props}
    assert props["pairflock_model"] == "pair_quad3d" and len(props["pairflock_sha256"]) == 64
