"""Chain identification (thesis §3.3.1, Eqs. 3.9-3.12): the regressor, total least squares scaled by a
known payload, recovery from generated recordings, and ``dgraph identify``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import yaml

from dgraph.cli import main
from dgraph.entities.actuators import identification as idn
from dgraph.entities.actuators.chain import ChainParameters, friction, load_chain_file

TRUTH = idn.DEMO_CHAIN  # TALOS's elbow (Table 3.1), R K_m = 5.3 N m/A
PAYLOAD = idn.DEMO_PAYLOAD  # 2 kg at 0.25 m
NAMES = (*idn.PHI_NAMES, "R_Km", "K_j")
# Recovery bounds (relative) from the default noise (19-bit encoder, 0.02 A, 0.1 N m), about 2.5x the worst
# errors measured over eight seed pairs (demo_recordings(seed=0, 2, ..., 14), velocity differentiated or
# recorded): R K_m 0.027 %, K_j 0.023 %, M_X 0.09 %, M_Y 0.045 %, F_vm 0.12 %, F_sm 0.066 %, F_vj 0.36 %,
# F_sj 0.24 %, off_m 0.28 %, off_j 0.49 %, I_j 0.42 %, I_m 1.4 % (a bias that remains without noise:
# filtering the nonlinear sign(q_dot) and sin q), the payload's I_p 1.7 %. A wrong regressor (I_j missing from
# the motor row) moves I_m by 73 %, a payload mass off by 1 % moves R K_m by 1 %.
TOLERANCE = {"R_Km": 7e-4, "K_j": 6e-4, "M_X": 2.5e-3, "M_Y": 1.2e-3, "F_vm": 3e-3, "F_sm": 1.7e-3, "F_vj": 9e-3,
             "F_sj": 6e-3, "off_m": 7e-3, "off_j": 0.012, "I_m": 0.035, "I_j": 0.011}
I_P_TOLERANCE = 0.045


def exact_samples(params: ChainParameters, payload: idn.Payload | None, seed: int, n: int = 400) -> idn.Samples:
    """Noise-free samples: random states, current and torque from Eqs. 3.1-3.4 written out directly."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.35, 0.0, n)
    qd = rng.uniform(0.1, 1.5, n) * rng.choice([-1.0, 1.0], n)
    qdd = rng.uniform(-4.0, 4.0, n)
    m_x, m_y, i_p = (0.0, payload.first_moment, payload.inertia) if payload else (0.0, 0.0, 0.0)
    gravity = 9.81 * ((params.M_Y + m_y) * np.sin(q) + (params.M_X + m_x) * np.cos(q))
    tau_fj = friction(params.F_vj, params.F_sj, params.off_j, qd)
    tau_j = (params.I_j + i_p) * qdd + gravity + tau_fj
    tau_m = tau_j + params.I_m * qdd + friction(params.F_vm, params.F_sm, params.off_m, qd)
    return idn.Samples(q, qd, qdd, tau_m / params.R_Km, tau_j / params.K_j, payload)


@pytest.fixture(scope="module")
def recordings():
    return idn.demo_recordings()


@pytest.fixture(scope="module")
def identified(recordings):
    plain, loaded = recordings
    return idn.identify([idn.samples_of(plain), idn.samples_of(loaded, PAYLOAD)])


def relative_errors(result: idn.Identification) -> dict[str, float]:
    return {name: result.estimates[name] / getattr(TRUTH, name) - 1 for name in NAMES}


def test_the_regressor_is_eq_3_1():
    samples = exact_samples(TRUTH, None, seed=1)
    w_m, w_j = idn.regressor(samples.q, samples.qd, samples.qdd)
    phi = idn.phi_of(TRUTH)
    assert np.allclose(w_m @ phi, TRUTH.R_Km * samples.current, atol=1e-12)
    assert np.allclose(w_j @ phi, TRUTH.K_j * samples.torque, atol=1e-12)
    assert np.all(w_j[:, 2:6] == 0) and np.all(w_m[:, 2:6] == w_m[:, 6:10])  # [G, D, D] and [G, 0, D]


def test_noise_free_data_recovers_every_parameter_to_1e_6():
    result = idn.identify([exact_samples(TRUTH, None, 2), exact_samples(TRUTH, PAYLOAD, 3)])
    assert max(abs(e) for e in relative_errors(result).values()) < 1e-6
    assert result.payload["I_p"] == pytest.approx(PAYLOAD.inertia, rel=1e-6)
    assert abs(result.payload["M_Xp"]) < 1e-6 and result.payload["M_Yp"] == PAYLOAD.first_moment
    assert result.singular_values[-1] < 1e-9 * result.singular_values[0]  # W_tot is rank deficient
    assert result.rmsd < 1e-9
    assert isinstance(result.parameters, ChainParameters) and result.parameters.i_max == TRUTH.i_max


def test_generated_recordings_recover_the_parameters_within_tolerance(identified):
    errors = relative_errors(identified)
    assert {name: e for name, e in errors.items() if abs(e) > TOLERANCE[name]} == {}
    assert identified.parameters.R_Km == pytest.approx(5.3, rel=TOLERANCE["R_Km"])
    assert identified.payload["I_p"] == pytest.approx(PAYLOAD.inertia, rel=I_P_TOLERANCE)


def test_cond_and_sigma_are_reported(identified, recordings):
    plain = idn.samples_of(recordings[0])
    assert identified.cond == pytest.approx(np.linalg.cond(np.vstack(idn.regressor(plain.q, plain.qd, plain.qdd))))
    assert 1 < identified.cond < 200  # the thesis's S-curves: cond(W_b) = 36
    assert np.isnan(identified.sigma_percent["M_Yp"])  # known, not estimated
    sigmas = [identified.sigma_percent[name] for name in NAMES]
    assert all(0 < s < 2 for s in sigmas)
    noisier = idn.identify([idn.samples_of(r, p) for r, p in zip(
        idn.demo_recordings(noise=idn.Noise(current_std=0.1, torque_std=0.5)), (None, PAYLOAD), strict=True)])
    assert all(noisier.sigma_percent[name] > identified.sigma_percent[name] for name in NAMES)
    table = identified.table()
    assert "cond(W) = " in table and all(name in table for name in NAMES)


def test_without_the_payload_experiment_the_scale_is_unidentifiable():
    plain = exact_samples(TRUTH, None, 4)
    with pytest.raises(ValueError, match="unidentifiable"):
        idn.identify([plain])
    w_tot = idn.total_regressor([plain])[:, :len(NAMES)]
    truth = np.array([*idn.phi_of(TRUTH), TRUTH.R_Km, TRUTH.K_j])
    for scale in (0.5, 1.0, 2.0):  # every multiple fits the data exactly
        assert np.linalg.norm(w_tot @ (scale * truth)) < 1e-9 * np.linalg.norm(w_tot) * scale
    # a known R K_m fixes it instead
    result = idn.identify([plain], drive_gain=TRUTH.R_Km)
    assert max(abs(e) for e in relative_errors(result).values()) < 1e-6


def test_a_wrong_payload_mass_scales_every_estimate(recordings, identified):
    heavier = replace(PAYLOAD, mass=PAYLOAD.mass * 1.1)
    wrong = idn.identify([idn.samples_of(recordings[0]), idn.samples_of(recordings[1], heavier)])
    assert wrong.estimates["R_Km"] / identified.estimates["R_Km"] == pytest.approx(1.1, rel=1e-9)
    assert wrong.estimates["F_sm"] / identified.estimates["F_sm"] == pytest.approx(1.1, rel=1e-9)
    assert abs(wrong.estimates["R_Km"] / TRUTH.R_Km - 1) > 0.09


def test_the_recorded_velocity_can_replace_the_differentiated_position(recordings):
    plain, loaded = recordings
    result = idn.identify([idn.samples_of(plain, use_velocity=True),
                           idn.samples_of(loaded, PAYLOAD, use_velocity=True)])
    assert {name: e for name, e in relative_errors(result).items() if abs(e) > TOLERANCE[name]} == {}


def test_the_excitation_is_the_thesis_double_s_curve():
    t, q, qd, qdd = idn.s_curve_excitation(v_max=1.5, dt=1e-3)
    assert q.min() == pytest.approx(-2.35, abs=1e-9) and q.max() == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(np.gradient(q, t), qd, atol=2e-3) and np.allclose(np.gradient(qd, t), qdd, atol=0.1)
    moving = np.flatnonzero(np.abs(qd) > 1e-9)
    starts = np.concatenate([[moving[0]], moving[1:][np.diff(moving) > 1]])
    ends = np.concatenate([moving[:-1][np.diff(moving) > 1], [moving[-1]]])
    peaks = [np.abs(qd[a:b + 1]).max() for a, b in zip(starts, ends, strict=True)]
    assert np.allclose(peaks, np.repeat([0.3, 0.6, 0.9, 1.2, 1.5], 2), rtol=0.01)  # plateaus in 20 % steps
    for a, b in zip(starts, ends, strict=True):  # equal acceleration, plateau and deceleration phases
        plateau = np.flatnonzero(np.abs(np.abs(qd[a:b + 1]) - np.abs(qd[a:b + 1]).max()) < 1e-6)
        assert (plateau[-1] - plateau[0]) / (b - a) == pytest.approx(1 / 3, abs=0.01)


def test_dgraph_identify_prints_the_table_and_writes_yaml(tmp_path, capsys):
    plain, loaded = idn.write_demo_recordings(tmp_path)
    out = tmp_path / "elbow.yaml"
    code = main(["identify", str(plain), "--payload-recording", str(loaded), "--payload-mass", "2",
                 "--payload-arm", "0.25", "--yaml", str(out), "--joint-name", "arm_left_4_joint", "--i-max", "6"])
    printed = capsys.readouterr().out
    assert code == 0, printed
    rows = {line.split()[0]: line.split()[1:] for line in printed.splitlines() if line.split()}
    assert float(rows["R_Km"][0]) == pytest.approx(5.3, rel=TOLERANCE["R_Km"])
    assert float(rows["K_j"][0]) == pytest.approx(1.015, rel=TOLERANCE["K_j"])
    assert "cond(W)" in printed and "sigma%" in printed
    # the written file is an actuator file: load_chain_file reads it back, equal to the estimates
    chains = load_chain_file(out)
    assert list(chains) == ["arm_left_4_joint"]
    params = chains["arm_left_4_joint"]
    plain_rec, loaded_rec = (idn.load_recording(p) for p in (plain, loaded))
    expected = idn.identify([idn.samples_of(plain_rec), idn.samples_of(loaded_rec, PAYLOAD)])
    assert params == replace(ChainParameters(), **expected.yaml_mapping(), i_max=6.0)  # exact: floats round-trip
    assert params.R_Km == pytest.approx(5.3, rel=TOLERANCE["R_Km"])
    assert "arm_left_4_joint" in yaml.safe_load(out.read_text())["joints"]


def test_dgraph_identify_yaml_needs_the_joint_and_i_max(tmp_path, capsys):
    plain, _ = idn.write_demo_recordings(tmp_path)
    out = tmp_path / "elbow.yaml"
    base = ["identify", str(plain), "--drive-gain", "5.3", "--yaml", str(out)]
    assert main(base) == 2 and "--joint-name" in capsys.readouterr().err
    assert main([*base, "--joint-name", "elbow"]) == 2 and "--i-max" in capsys.readouterr().err
    assert main([*base, "--joint-name", "elbow", "--i-max", "-1"]) == 2 and not out.exists()
    assert main([*base, "--joint-name", "elbow", "--i-max", "inf"]) == 0
    assert load_chain_file(out)["elbow"].i_max == float("inf")


def test_a_payload_arm_of_the_wrong_sign_is_refused(recordings):
    flipped = idn.Payload(PAYLOAD.mass, -PAYLOAD.arm)
    with pytest.raises(ValueError, match=r"R_Km = -.*K_j = -.*sign of the payload's arm"):
        idn.identify([idn.samples_of(recordings[0]), idn.samples_of(recordings[1], flipped)])
    with pytest.raises(ValueError, match="R_Km = -5.3.*drive_gain"):
        idn.identify([exact_samples(TRUTH, None, 4)], drive_gain=-5.3)


def test_dgraph_identify_refuses_a_npy_file_and_names_it(tmp_path, capsys):
    bad = tmp_path / "x.npy"
    np.save(bad, np.zeros((10, 4)))
    assert main(["identify", str(bad), "--drive-gain", "5.3"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "not an .npz archive" in err
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"PK\x03\x04 not a zip")
    assert main(["identify", str(junk), "--drive-gain", "5.3"]) == 2 and str(junk) in capsys.readouterr().err


def test_a_nan_in_a_column_is_named_with_its_first_sample(tmp_path, capsys, recordings):
    data = dict(recordings[0])
    data["position"] = data["position"].copy()
    data["position"][[1234, 5000]] = np.nan
    path = tmp_path / "nan.npz"
    np.savez(path, **data)
    assert main(["identify", str(path), "--drive-gain", "5.3"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "column 'position' (position) is not finite at 2 sample(s), the first at sample 1234" \
        in err
    with pytest.raises(ValueError, match="column 'torque' is not finite at 1 sample.*sample 7"):
        torque = data["torque"].copy()
        torque[7] = np.inf
        idn.prepare(data["time"], recordings[0]["position"], data["current"], torque)


def test_dgraph_identify_names_the_missing_column_and_exits_2(tmp_path, capsys):
    plain, loaded = idn.write_demo_recordings(tmp_path)
    code = main(["identify", str(plain), "--payload-recording", str(loaded), "--payload-mass", "2",
                 "--payload-arm", "0.25", "--current", "elbow.i_m"])
    err = capsys.readouterr().err
    assert code == 2 and str(plain) in err and "'elbow.i_m'" in err
    assert main(["identify", str(plain)]) == 2  # no payload and no R K_m: the scale is unknown
    assert "unidentifiable" in capsys.readouterr().err
    assert main(["identify", str(plain), "--drive-gain", "5.3"]) == 0
    assert main(["identify", str(plain), "--payload-mass", "2"]) == 2
