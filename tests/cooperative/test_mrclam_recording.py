"""MRCLAM dataset → Recording (:func:`relloc.datasets.mrclam.to_recording`)."""

import pickle
import shutil

import numpy as np

from relloc.core.recording import kind_code
from relloc.datasets.mrclam import REPEATED_READING, UNMAPPED_SUBJECT, load_mrclam, to_recording

ROBOT_2_BARCODE = 14  # as the synthetic folder (conftest) assigns them
N_LANDMARKS = 6


def test_synthetic_folder_converts_row_for_row(synthetic_mrclam):
    ds = load_mrclam(synthetic_mrclam)
    rec = to_recording(ds)
    assert rec.robots == ("1", "2", "3", "4", "5") and rec.platforms == ("ground",) * 5
    assert rec.landmarks.shape == (N_LANDMARKS, 3)
    assert np.array_equal(rec.landmarks[:, :2], ds.landmarks.xy)
    m = rec.measurements
    assert np.all(m.kind == kind_code("range_bearing"))
    assert m.size == sum(len(ds.robot(r).measurements) for r in ds.robot_ids)
    assert np.all(np.diff(m.t) >= 0)
    for i, rid in enumerate(ds.robot_ids):
        od, raw = rec.odometry[i], ds.robot(rid).odometry
        assert np.array_equal(od.t, raw.t)
        assert np.array_equal(od.velocity[:, [0, 3]], np.column_stack([raw.v, raw.omega]))
        assert not od.velocity[:, 1:3].any()
        mine = m.select(m.observer == i)
        loaded = ds.robot(rid).measurements
        assert np.array_equal(mine.value[:, :2], np.column_stack([loaded.range, loaded.bearing]))
        subject = np.where(mine.target >= 0, mine.target + 1, mine.landmark + 6)
        assert np.array_equal(subject, loaded.subject)
    assert rec.skips.skipped_by_reason() == ds.report.skipped_by_reason() == {"unknown barcode": 1}
    assert pickle.loads(pickle.dumps(rec)).meta == rec.meta


def test_readings_a_recording_cannot_hold_are_counted(synthetic_mrclam, tmp_path):
    folder = tmp_path / "odd"
    shutil.copytree(synthetic_mrclam, folder)
    path = folder / "Robot2_Measurement.dat"
    lines = path.read_text().splitlines(keepends=True)
    row = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    stamp = lines[row].split("\t")[0]
    own = f"{stamp}\t{ROBOT_2_BARCODE}\t1.0\t0.1\n"  # robot 2 sees itself
    lines[row + 1 : row + 1] = [lines[row], own]  # and the same reading twice
    path.write_text("".join(lines))
    ds = load_mrclam(folder)
    rec = to_recording(ds)
    assert rec.measurements.size == sum(len(ds.robot(r).measurements) for r in ds.robot_ids) - 2
    skipped = {f.file: f for f in rec.skips.files}["Robot2_Measurement.dat"]
    assert skipped.skipped == {UNMAPPED_SUBJECT: 1, REPEATED_READING: 1}
    assert skipped.rows_read == skipped.rows_kept + skipped.n_skipped
