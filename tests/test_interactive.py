"""The sliders' update functions: plain functions that draw and return the numbers they show.

ipywidgets is never imported here: the widget builders only wire sliders to
these functions, which is all the notebooks' interactive layer adds.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402

from course import diagnosis as dg  # noqa: E402
from course import filters as kf  # noqa: E402
from course import interactive, lsq  # noqa: E402
from course import mismatched as mm  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def test_importing_the_module_needs_no_ipywidgets():
    # only the widget builders import ipywidgets, lazily
    source = open(interactive.__file__, encoding="utf-8").read()
    head = source.split("def _ipywidgets")[0]
    assert "import ipywidgets" not in head


def test_omt_view_agrees_with_the_library_and_the_power_formula():
    no_outlier = interactive.omt_view(alpha=0.05, outlier=0.0)
    t, y = lsq.load_sea_level(0)
    fit = lsq.fit(np.column_stack([np.ones_like(t), t]), y, 4.0 * np.eye(t.size))
    assert no_outlier["T"] == pytest.approx(lsq.overall_model_test(fit, 0.05).statistic)
    assert no_outlier["omt_power"] == pytest.approx(0.05)
    assert no_outlier["w_power"] == pytest.approx(0.05)
    big = interactive.omt_view(alpha=0.05, outlier=15.0)
    assert big["omt_reject"] and 4 in big["w_reject"]
    # the w-test is the most powerful test against one outlier: more power than the OMT
    assert 0.05 < big["omt_power"] < big["w_power"] <= 1.0
    # a larger alpha can only enlarge the critical region
    assert (
        interactive.omt_view(alpha=0.2, outlier=5.0)["w_power"]
        > interactive.omt_view(alpha=0.01, outlier=5.0)["w_power"]
    )


def _signals():
    t = np.arange(50)
    return np.column_stack(
        [
            1.0 + 0.5 * np.sin(2 * np.pi * t / 25),
            np.cos(2 * np.pi * t / 16) + 0.3,
            np.where((t // 10) % 2 == 0, 1.0, -0.5),
        ]
    )


def test_power_view_is_alpha_without_fault_and_blind_to_the_decoupled_fault():
    U = _signals()
    at = interactive.power_view(0.0, 0.05, 0.2, U=U, nominal=np.ones(3), free=[0])
    assert at == pytest.approx({"F1": 0.05, "F2": 0.05, "F3": 0.05})
    at = interactive.power_view(0.2, 0.05, 0.2, U=U, nominal=np.ones(3), free=[0])
    assert at["F1"] == pytest.approx(0.05)  # theta_1 is free: its fault is decoupled
    theta = np.array([1.0, 1.2, 1.0])
    assert at["F2"] == pytest.approx(
        dg.prediction_error_power(U, np.ones(3), [0], theta, sigma=0.2, alpha=0.05)
    )
    noisier = interactive.power_view(0.2, 0.05, 0.4, U=U, nominal=np.ones(3), free=[0])
    assert noisier["F2"] < at["F2"]


def test_ekf_view_trades_false_alarms_against_detection():
    quiet = interactive.ekf_view(q_beta=1e-4, fault_size=0.0, runs=200)
    # no fault: the per-sample alarm rate is near the design alpha = 0.001
    assert quiet["false_alarm_rate"] < 0.01 and quiet["detection"] < 0.1
    stiff = interactive.ekf_view(q_beta=0.0, fault_size=0.0, runs=200)
    assert (
        stiff["false_alarm_rate"] > 10 * quiet["false_alarm_rate"]
    )  # beta cannot follow the drift
    loud = interactive.ekf_view(q_beta=1e-4, fault_size=0.3, runs=200)
    assert loud["detection"] > 0.9


def test_nis_view_power_is_alpha_under_h0_and_the_matrix_test_sees_correlation():
    h0 = interactive.nis_view(correlation=0.0, anisotropy=1.0, K=30, runs=4000)
    for key in ("nis_power", "matrix_power"):
        lo, hi = stats.binom.interval(0.999, 4000, 0.05)
        assert lo / 4000 <= h0[key] <= hi / 4000
    corr = interactive.nis_view(correlation=0.8, anisotropy=1.0, K=50, runs=2000)
    assert corr["matrix_power"] > 0.8 > corr["nis_power"]
    assert corr["eigenvalues"] == pytest.approx((0.2, 1.8))


def test_records_view_matches_the_library_power_and_grows_with_M():
    M0 = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.5]], R=[[1.0]], x0_cov=[[1.0]])
    M1 = kf.LinearModel(F=[[0.8]], H=[[1.0]], Q=[[1.0]], R=[[1.0]], x0_cov=[[1.0]])
    M2 = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[1.5]], R=[[1.0]], x0_cov=[[1.0]])
    null, alt = mm.residual_moments(M0, M1, 6), mm.residual_moments(M2, M1, 6)
    small = interactive.records_view(5, null=null, alternative=alt, j=4, k=5)
    large = interactive.records_view(40, null=null, alternative=alt, j=4, k=5)
    assert small["covariance"] == pytest.approx(mm.power(null, alt, "covariance", 4, 5), rel=1e-6)
    assert large["covariance"] > small["covariance"]


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: interactive.omt_view(alpha=0.0), "alpha"),
        (lambda: interactive.omt_view(outlier=np.nan), "outlier"),
        (lambda: interactive.nis_view(correlation=1.0), "correlation"),
        (lambda: interactive.nis_view(K=1), "K"),
        (lambda: interactive.ekf_view(q_beta=-1.0), "q_beta"),
    ],
)
def test_update_functions_refuse_bad_slider_values(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_glr_view_agrees_with_the_tests_and_their_alternative_laws():
    t = np.arange(1.0, 21.0)
    A = np.column_stack([np.ones_like(t), t])
    fit = lsq.fit(A, np.zeros(20), 4.0 * np.eye(20))
    shown = interactive.glr_view(size=6.0, alpha=0.05)
    c4 = np.eye(20)[:, 4]
    # the bias 6 c4 written in each alternative's own columns
    single = lsq.glr_test(fit, c4, 0.05).power(lsq.alternative_law(fit, c4, 6.0))
    pair = np.eye(20)[:, [4, 5]]
    double = lsq.glr_test(fit, pair, 0.05).power(lsq.alternative_law(fit, pair, [6.0, 0.0]))
    overall = lsq.overall_model_test(fit, 0.05).power(
        stats.ncx2(18, 36.0 * fit.redundancy_numbers[4] / 4.0)
    )
    assert shown["q = 1"] == pytest.approx(single, rel=1e-9)
    assert shown["q = 2"] == pytest.approx(double, rel=1e-9)
    assert shown["q = 18"] == pytest.approx(overall, rel=1e-9)
    assert shown["q = 1"] > shown["q = 2"] > shown["q = 18"] > 0.05  # the narrowest test wins
    assert interactive.glr_view(size=0.0, alpha=0.01)["q = 18"] == pytest.approx(0.01)


def test_b_method_view_agrees_with_the_library():
    shown = interactive.b_method_view(alpha_1=0.001, power=0.8)
    b = lsq.b_method(0.001, 0.8, [2, 5, 18, 30])
    assert shown["lambda0"] == pytest.approx(b.lambda0)
    assert [shown[f"alpha_{q}"] for q in (2, 5, 18, 30)] == pytest.approx(list(b.alpha_q))
    with pytest.raises(ValueError, match="power must exceed"):
        interactive.b_method_view(alpha_1=0.5, power=0.3)


def test_widget_builders_wire_sliders_that_redraw_on_release():
    pytest.importorskip("ipywidgets")
    widget = interactive.omt_widget()
    sliders = [s for row in widget.children[:2] for s in row.children]
    assert [s.description for s in sliders] == ["α", "outlier [record units]"]
    assert all(s.continuous_update is False for s in sliders)
    area = widget.children[2]
    first = area.outputs
    assert [o["output_type"] for o in first] == ["display_data"]
    assert "Figure" in first[0]["data"]["text/plain"]
    sliders[1].value = 3.0  # moving a slider redraws the figure
    assert area.outputs is not first and "Figure" in area.outputs[0]["data"]["text/plain"]
    assert plt.get_fignums() == []  # each figure lives on in the output area only
    U = _signals()
    assert interactive.power_widget(U=U, nominal=np.ones(3), free=[0]) is not None
    assert interactive.glr_widget() is not None and interactive.b_method_widget() is not None


def test_a_slider_value_the_update_refuses_is_shown_in_the_output_area():
    pytest.importorskip("ipywidgets")

    def update(x):
        plt.subplots()
        if x > 1:
            raise ValueError(f"x must be at most 1, got {x}")

    slider = interactive._slider("float", "x", 0.5, 0.0, 2.0, 0.5)
    area = interactive._build(update, {"x": slider}).children[2]
    slider.value = 2.0
    assert area.outputs == (
        {
            "output_type": "stream",
            "name": "stderr",
            "text": "ValueError: x must be at most 1, got 2.0\n",
        },
    )
    assert plt.get_fignums() == []  # the half-drawn figure is closed too


def test_a_widget_cell_run_without_a_browser_sends_nothing_back_to_the_kernel(tmp_path):
    """A notebook runner without a browser (nbconvert, ``jupyter execute``, the website build:
    all nbclient) mimics the browser's Output widget and sends every output captured by
    ``with output:`` back to the kernel on the shell socket while it waits there for the cell's
    reply; that send can swallow the reply's wake-up, and the run then sat idle for the whole
    cell timeout (nbclient#312: notebooks 01, 04 and 06 took 20-60 s longer on a loaded
    machine). The sliders set their figure into the widget from the kernel: nothing is sent."""
    pytest.importorskip("ipywidgets")
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")

    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(
            "%matplotlib inline\nfrom course import interactive\ninteractive.omt_widget()"
        )
    ]
    sent = []

    def record_shell_sends(notebook):
        send = client.kc.shell_channel.send

        def recording(msg):
            sent.append(msg["msg_type"])
            send(msg)

        client.kc.shell_channel.send = recording

    client = nbclient.NotebookClient(
        nb,
        timeout=120,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
        on_notebook_start=record_shell_sends,
    )
    client.execute()
    assert "execute_request" in sent  # the recording saw the runner's requests
    assert "comm_msg" not in sent, sent
    # and the student still sees the figure: a PNG in the widget's output area
    (area,) = [s for s in client.widget_state.values() if s.get("_model_name") == "OutputModel"]
    assert [o["output_type"] for o in area["outputs"]] == ["display_data"]
    assert "image/png" in area["outputs"][0]["data"]


def test_omt_view_legend_shows_only_what_is_drawn_and_both_panels_have_titles():
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2)
    view = interactive.omt_view(alpha=0.05, outlier=0.0, axes=axes)
    assert not view["w_reject"]
    labels = [text.get_text() for text in axes[1].get_legend().get_texts()]
    assert "rejected" not in labels and "accepted" in labels
    assert axes[0].get_title() and axes[1].get_title()
    plt.close(fig)
    fig, axes = plt.subplots(1, 2)
    interactive.omt_view(alpha=0.05, outlier=15.0, axes=axes)
    labels = [text.get_text() for text in axes[1].get_legend().get_texts()]
    assert "rejected" in labels and "reject" in axes[0].get_title()
    plt.close(fig)
