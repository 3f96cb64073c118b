"""The track figure's surface zoom: which rows are a surface movement worth a panel, and the panels drawn."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.report.track_figures import surface_parts, track_figure

KM_PER_DEG = 6371.0088 * np.pi / 180.0


def _flight(taxi_s: int = 300, air_s: int = 240, arrival_taxi_s: int = 0) -> pd.DataFrame:
    """A track table by hand: taxi at 10 kt east along the equator, fly east at 250 kt, maybe taxi again."""
    speeds = np.r_[np.full(taxi_s, 10.0), np.full(air_s, 250.0), np.full(arrival_taxi_s, 12.0)]
    east_km = np.cumsum(speeds * 1.852 / 3600.0)  # 1 s rows
    n = len(speeds)
    return pd.DataFrame({
        "aircraft_id": "ABC123",
        "time": pd.Timestamp("2026-01-01", tz="UTC") + pd.to_timedelta(np.arange(n), "s"),
        "latitude": 0.001 * np.sin(np.arange(n) / 50.0), "longitude": east_km / KM_PER_DEG,
        "speed_kt": speeds, "coasted": np.arange(n) % 4 == 3, "segment": 0,
        "sigma_major_m": 20.0, "sigma_minor_m": 10.0, "ellipse_orientation_deg": 0.0,
        "mode_cv": 0.9, "mode_turn_left": 0.05, "mode_turn_right": 0.05})


def _parts(t: pd.DataFrame) -> list[np.ndarray]:
    e = t["longitude"].to_numpy() * KM_PER_DEG
    nn = t["latitude"].to_numpy() * KM_PER_DEG
    span = max(np.ptp(e), np.ptp(nn))
    return surface_parts(t["speed_kt"].to_numpy(), t["coasted"].to_numpy(), e, nn, span)


def test_a_taxi_before_a_flight_is_one_part_of_exactly_its_rows():
    # 300 s at 10 kt is 1.54 km, the flight 240 s at 250 kt 30.9 km: the taxi is 5 % of the map
    (part,) = _parts(_flight())
    assert part.tolist() == list(range(300))


def test_departure_and_arrival_taxis_far_apart_are_two_parts_in_time_order():
    first, second = _parts(_flight(arrival_taxi_s=200))
    assert first.tolist() == list(range(300)) and second.tolist() == list(range(540, 740))


def test_no_zoom_for_a_big_taxi_a_lone_coasted_report_or_a_parked_aircraft():
    assert _parts(_flight(taxi_s=3000, air_s=60)) == []  # the taxi (15 km) is most of the map
    t = _flight(taxi_s=40)
    t["coasted"] = np.arange(len(t)) > 0  # one report, then 39 s coasted at 10 kt: no taxi seen
    assert _parts(t) == []
    assert _parts(_flight(taxi_s=600, air_s=0)) == []  # parked or taxiing only: the map is the taxi


def test_the_figure_zooms_on_the_taxi_and_marks_it_on_the_map():
    t = _flight()
    reports = pd.DataFrame({"sensor_id": "021:0/1", "sensor_kind": "adsb", "time": t["time"],
                            "latitude": t["latitude"], "longitude": t["longitude"]})
    fig = track_figure(t, reports, "ABC123")
    ax, zoom, _ = fig.axes
    e = (t["longitude"] - t["longitude"].median()).to_numpy() * KM_PER_DEG
    taxi = slice(0, 300)
    x0, x1 = zoom.get_xlim()
    assert x0 < e[taxi].min() and e[taxi].max() < x1 and (x1 - x0) < 0.1 * np.ptp(e)
    mx0, mx1 = ax.get_xlim()
    assert mx0 < e.min() and e.max() < mx1
    assert [p.get_width() for p in ax.patches if type(p).__name__ == "Rectangle"] == [x1 - x0]
    assert len(track_figure(_flight(taxi_s=0), reports.iloc[300:], "ABC123").axes) == 2


def test_mode_lines_break_between_segments_and_short_tracks_tick_seconds():
    """Two segments 4 min apart: each mode is drawn as one line per segment, none across the gap; tick labels
    never repeat, and a 150 s track's carry seconds (minutes alone repeated '22:03' on short tracks)."""
    t = _flight(taxi_s=240, air_s=0, arrival_taxi_s=0)
    second = t.assign(time=t["time"] + pd.Timedelta(minutes=8), segment=1)
    t = pd.concat([t, second], ignore_index=True)
    reports = pd.DataFrame({"sensor_id": "021:0/1", "sensor_kind": "adsb", "time": t["time"],
                            "latitude": t["latitude"], "longitude": t["longitude"]})
    fig = track_figure(t, reports, "ABC123")
    mode_ax = fig.axes[-1]
    cv = [line for line in mode_ax.get_lines() if line.get_color() == "#444444"]
    assert len(cv) == 2 and [len(line.get_xdata()) for line in cv] == [240, 240]
    fig.canvas.draw()
    labels = [tick.get_text() for tick in mode_ax.get_xticklabels() if tick.get_text()]
    assert labels and len(set(labels)) == len(labels)
    short = _flight(taxi_s=100, air_s=50)  # 150 s: ticks less than a minute apart show their seconds
    fig = track_figure(short, reports.iloc[:150], "ABC123")
    fig.canvas.draw()
    labels = [tick.get_text() for tick in fig.axes[-1].get_xticklabels() if tick.get_text()]
    assert len(labels) > 1 and len(set(labels)) == len(labels)
    assert all(len(text) == 8 and text.count(":") == 2 for text in labels)  # HH:MM:SS


def _reported_every(t: pd.DataFrame, every_s: int, silent: tuple[int, int] | None = None) -> pd.DataFrame:
    """The 1 s track rows with a report every ``every_s`` seconds (none inside ``silent``): ``coasted`` on
    every row between two reports, ``age_s`` the seconds since the last one, the sensor that gave it."""
    k = np.arange(len(t))
    reported = k % every_s == 0
    if silent is not None:
        reported &= ~((k > silent[0]) & (k < silent[1]))
    last = np.maximum.accumulate(np.where(reported, k, 0))
    return t.assign(coasted=~reported, age_s=(k - last).astype(float), time_of_day=k.astype(float),
                    sources=np.where(reported, "021:0/1", ""))


def test_rows_between_regular_reports_are_not_drawn_as_coasted():
    """On the 1 s grid, reports every 4 s leave three rows in four without a report (``coasted``): none
    is coasting (4 s is the update interval); 32 s without a report (reports at 100 s, then 132 s) is, from
    1.5 intervals (6 s) on: rows 107-131 (age 7-31 s)."""
    from msdc.pipeline.report.track_figures import coasting

    regular = _reported_every(_flight(), 4)
    assert regular["coasted"].mean() == 0.75 and not coasting(regular).any()
    silent = _reported_every(_flight(), 4, silent=(100, 130))
    assert np.flatnonzero(coasting(silent)).tolist() == list(range(107, 132))
    assert (coasting(_flight()) == _flight()["coasted"].to_numpy()).all()  # no age_s: the flags


def test_the_surface_zoom_draws_a_reported_taxi_solid():
    """The zoomed taxi of a track reported every 4 s: its dashed (coasted) line holds no point, where it
    held three rows in four."""
    t = _reported_every(_flight(), 4)
    reports = pd.DataFrame({"sensor_id": "021:0/1", "sensor_kind": "adsb", "time": t["time"],
                            "latitude": t["latitude"], "longitude": t["longitude"]})
    fig = track_figure(t, reports, "ABC123")
    zoom = fig.axes[1]
    dashed = [line for line in zoom.get_lines() if line.get_linestyle() != "-" and line.get_marker() in
              ("None", "", None)]
    assert dashed and all(np.isnan(np.asarray(line.get_xdata(), float)).all() for line in dashed)


def test_the_figure_ends_at_the_recordings_last_report():
    """The tracker coasts a minute past an aircraft's last report; at the end of the recording that
    minute is no data: rows after ``end`` are not drawn (map or mode panel), and the recording's end is
    its inputs' last report (any source), not the aircraft's."""
    import matplotlib.dates as mdates

    from msdc.pipeline.report.track_figures import recording_end

    t = _flight(taxi_s=300, air_s=0)
    end = t["time"].iloc[239]
    reports = pd.DataFrame({"sensor_id": "021:0/1", "sensor_kind": "adsb", "time": t["time"].iloc[:240],
                            "latitude": t["latitude"].iloc[:240], "longitude": t["longitude"].iloc[:240]})
    fig = track_figure(t, reports, "ABC123", end=end)
    mode = fig.axes[-1]
    last = max(np.asarray(line.get_xdata())[-1] for line in mode.get_lines())
    assert mdates.date2num(last) == pytest.approx(mdates.date2num(end.tz_convert(None)))
    assert sum(np.isfinite(np.asarray(line.get_xdata(), float)).sum() for line in fig.axes[0].get_lines()
               if line.get_color() == "#111111") <= 2 * 240

    class Loaded:
        spans = [{"021:0/1": (t["time"].iloc[0], end)},
                 {"048:25/201": (t["time"].iloc[0], t["time"].iloc[250])}]

    class Result:
        loaded, measurements = Loaded(), reports

    assert recording_end(Result()) == t["time"].iloc[250]
    Loaded.spans = None
    assert recording_end(Result()) == end


@pytest.mark.parametrize("arrival_taxi_s", [None, 0, 200])
def test_the_fixed_layout_keeps_every_text_in_the_figure_and_off_the_other_axes(arrival_taxi_s):
    """The figure is laid out by fixed margins, not constrained layout: with no zoom, one and two zoom
    panels, every tick label, axis label, title and legend lies inside the figure, and none of one axes'
    texts runs into another axes' plotting area."""
    t = _flight(taxi_s=0) if arrival_taxi_s is None else _flight(arrival_taxi_s=arrival_taxi_s)
    reports = pd.DataFrame({"sensor_id": "021:0/1", "sensor_kind": "adsb", "time": t["time"],
                            "latitude": t["latitude"], "longitude": t["longitude"]})
    fig = track_figure(t, reports, "ABC123 (A1B2C3)")
    assert len(fig.axes) == {None: 2, 0: 3, 200: 4}[arrival_taxi_s]
    renderer = fig.canvas.get_renderer()
    fig.draw(renderer)
    page = fig.bbox
    for ax in fig.axes:
        texts = [ax.xaxis.label, ax.yaxis.label, ax.title]
        for axis in (ax.xaxis, ax.yaxis):  # the tick labels drawn: those of ticks within the view
            lo, hi = sorted(axis.get_view_interval())
            texts += [label for at, label in zip(axis.get_majorticklocs(), axis.get_majorticklabels(),
                                                 strict=True) if lo <= at <= hi]
        boxes = [x.get_window_extent(renderer) for x in texts if x.get_visible() and x.get_text()]
        if ax.get_legend() is not None:
            boxes.append(ax.get_legend().get_window_extent(renderer))
        for box in boxes:
            assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
            for other in fig.axes:
                if other is not ax:
                    assert not box.overlaps(other.get_window_extent(renderer)), (ax.get_title(),
                                                                                 other.get_title())
