"""The live monitor page in a real headless Chromium (Debian's, through Playwright) with every request not to
the monitor refused: the fixture recording replayed 20x through a fake live state appears on the map within
2 s, its counters move, the radar's silent alarm is raised when its replay stops, nothing logs an error, and
a page that goes away leaves the server serving the next one."""

from __future__ import annotations

import json
import os
import shutil
import time

import pytest
from live_fake_state import ReplayState, fixture_measurements, running, synthetic_measurements

from msdc.pipeline.live.monitor import Thresholds

CHROMIUM = "/usr/bin/chromium"
RADAR = "048:25/201"
ADSB = "021:0/1"


def _browser():
    """Playwright's sync API and Debian's Chromium, or a skip saying which is missing."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("playwright not installed (pip install playwright): the monitor page is opened in "
                    "headless Chromium through it")
    if shutil.which(CHROMIUM) is None:
        pytest.skip(f"{CHROMIUM} not installed (apt-get install chromium): the monitor page is opened in it")
    return sync_playwright


def _figure(page, sensor: str, key: str) -> str:
    return page.text_content(f'.sensor[data-sensor-id="{sensor}"] td[data-figure="{key}"]')


@pytest.mark.slow  # Chromium's start, then about 6 s of replay
def test_the_monitor_page_in_chromium_offline() -> None:
    sync_playwright = _browser()
    frame = fixture_measurements()
    # silent after 1.5 s: the radar's scans come every 4.8 s / 20 = 0.24 s, the ADS-B's reports faster
    thresholds = Thresholds(silent_s=1.5, window_s=60.0)
    state = ReplayState(frame, speed=20.0)
    refused: list[str] = []
    messages: list[tuple[str, str]] = []
    with running(state, thresholds) as (url, thread, _), sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--no-first-run"])
        try:
            context = browser.new_context(viewport={"width": 1200, "height": 720})

            def route(r) -> None:
                if r.request.url.startswith(url):
                    r.continue_()
                else:
                    refused.append(r.request.url)
                    r.abort()

            context.route("**/*", route)
            page = context.new_page()
            page.on("console", lambda m: messages.append((m.type, m.text)))
            page.on("pageerror", lambda e: messages.append(("error", str(e))))
            opened = time.monotonic()
            page.goto(url)
            # both sensors' targets drawn (the first snapshot may come before the replay's first plot)
            page.wait_for_function(f"""() => {{
                const s = new Set([...document.querySelectorAll('#targets li')].map(l => l.dataset.sensor));
                return s.has('{RADAR}') && s.has('{ADSB}'); }}""", timeout=5000)
            drawn_after_s = time.monotonic() - opened
            listed = page.eval_on_selector_all("#targets li", "ls => ls.map(l => l.dataset.sensor)")
            before = _figure(page, RADAR, "records")
            seen = int(page.get_attribute("body", "data-snapshots"))
            page.wait_for_function(f"() => Number(document.body.dataset.snapshots) > {seen}", timeout=3000)
            after = _figure(page, RADAR, "records")
            assert page.query_selector('#alarms li[data-kind="silent"]') is None
            state.silence(RADAR)
            silenced = time.monotonic()
            page.wait_for_selector(f'#alarms li[data-kind="silent"][data-sensor="{RADAR}"]', timeout=5000)
            alarm_after_s = time.monotonic() - silenced
            alarms = page.eval_on_selector_all("#alarms li",
                                               "ls => ls.map(l => [l.dataset.kind, l.dataset.sensor])")
            radar_pd = _figure(page, RADAR, "pd")
            # every column of the feeds table in view at 1,200 px: none pushed past the side panel's edge
            assert page.evaluate("""() => {
                const side = document.querySelector('#side').getBoundingClientRect();
                const cells = [...document.querySelectorAll('#feeds th')];
                return cells.every(c => c.getBoundingClientRect().right <= side.right + 0.5); }""")
            if os.environ.get("MSDC_LIVE_MONITOR_SHOT"):  # the docs' picture: MSDC_LIVE_MONITOR_SHOT=path
                page.wait_for_timeout(1500)
                page.screenshot(path=os.environ["MSDC_LIVE_MONITOR_SHOT"])
            page.close()  # mid-stream
            second = context.new_page()
            second.on("console", lambda m: messages.append((m.type, m.text)))
            second.goto(url)
            second.wait_for_function("() => Number(document.body.dataset.snapshots) > 0", timeout=3000)
            server_alive = thread.is_alive()
        finally:
            browser.close()
    # the replay's targets: radar and ADS-B both on the map within 3 s of opening the page (a snapshot a
    # second, the radar's first plot replayed within the first)
    assert drawn_after_s < 3.0
    assert {RADAR, ADSB} <= set(listed)
    # the radar's records counter moved between two snapshots (the replay sends a scan every 0.24 s)
    assert before != after and int(after.split(" / ")[1]) > int(before.split(" / ")[1])
    # silent 1.5 s after the radar's last report (at most 0.25 s before the replay stopped), seen at the
    # next snapshot (a second later at most); the ADS-B, still replayed, not
    assert 1.25 <= alarm_after_s < 4.0
    assert alarms == [["silent", RADAR]]
    assert radar_pd != "–"  # the radar's live probability of update is measured on its replayed scans
    assert server_alive
    assert refused == []
    assert [m for m in messages if m[0] in ("error", "warning")] == []


def _withheld(note: str) -> dict:
    return {"value": None, "ci_low": None, "ci_high": None, "count": 0, "n": 0, "threshold": 0.97,
            "state": "withheld", "note": note}


def _snapshot_at(now_wall_s: float, uptime_s: float) -> dict:
    """A snapshot written by hand (schema msdc-live-monitor/1) made at now_wall_s, uptime_s after the start:
    one radar heard 2 s ago, 90 reports in the window (2 a second over the uptime), one feed of 550 packets
    (12.5 a second over the uptime less 1 s, since its first snapshot), no target."""
    radar = {"sensor_id": RADAR, "kind": "radar", "feeds": ["udp:239.1.2.3:8600"], "records_total": 90,
             "reports_in_window": 90, "reports_per_s": 2.0, "rate_window_s": uptime_s,
             "figures_sample": None, "update_interval_s": None,
             "update_interval_note": "too few", "last_report_age_s": 2.0, "last_status_age_s": None,
             "decode_errors": 0, "pd": _withheld("too few"), "mode3a_valid": _withheld("too few"),
             "modec_valid": _withheld("too few"), "alarms": []}
    feed = {"feed": "udp:239.1.2.3:8600", "packets": 550, "bytes": 33000, "framed": 550, "unframed": 0,
            "empty": 0, "decode_errors": 0, "dropped": 0, "waiting": 0, "packets_per_s": 12.5,
            "rate_window_s": uptime_s - 1.0, "decode_errors_in_window": 0, "dropped_in_window": 0,
            "unframed_in_window": 0, "last_packet_age_s": 0.5}
    thresholds = {"silent_s": 30.0, "min_pd": 0.97, "min_mode3a_valid": 0.98, "min_modec_valid": 0.96,
                  "window_s": 120.0}
    return {"schema": "msdc-live-monitor/1", "now_wall_s": now_wall_s,
            "started_wall_s": now_wall_s - uptime_s,
            "uptime_s": uptime_s, "alarms": [], "sensors": [radar], "feeds": [feed], "centre": None,
            "targets": [], "thresholds": thresholds}


def _lost_state(page) -> dict:
    """What the page shows of its connection: the lost banner (None when hidden), whether its figures are
    marked stale, how opaque the figures are drawn, and its clock."""
    return page.evaluate("""() => ({
        lost: document.getElementById('lost').hidden ? null : document.getElementById('lost').textContent,
        stale: document.body.classList.contains('stale'),
        opacity: Number(getComputedStyle(document.querySelector('main')).opacity),
        clock: document.getElementById('clock').textContent})""")


@pytest.mark.slow  # Chromium's start, then about 10 s of streams dropped and restored
def test_a_page_that_loses_its_connection_says_since_when_and_greys_its_figures() -> None:
    """The page froze on "reconnecting…" with its last figures looking current after listen stopped. Its
    stream is first one snapshot made at 1,800,000,000 s (2027-01-15 08:00:00 UTC: 20,833 days and 28,800 s),
    then refused: the page says the connection is lost since 08:00:00 UTC and greys its figures. Let through
    to the real server, it is live again; when the server stops, it is lost again since its last snapshot."""
    sync_playwright = _browser()
    mode = {"events": "written"}  # the event stream: the snapshot written here, refused, or the server's
    written = "retry: 300\nid: 1\ndata: " + json.dumps(_snapshot_at(1_800_000_000.0, 45.0)) + "\n\n"
    errors: list[str] = []
    state = ReplayState(synthetic_measurements(), speed=20.0, start_wall_s=time.time() - 10.0)
    with running(state, Thresholds(window_s=30.0)) as (url, thread, stop), sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
        try:
            context = browser.new_context(viewport={"width": 1200, "height": 720})

            def route(r) -> None:
                if r.request.url != url + "events" or mode["events"] == "server":
                    r.continue_() if r.request.url.startswith(url) else r.abort()
                elif mode["events"] == "written":
                    mode["events"] = "refused"  # the stream ends after its one snapshot, then is refused
                    r.fulfill(status=200, headers={"Content-Type": "text/event-stream"}, body=written)
                else:
                    r.abort("connectionrefused")

            context.route("**/*", route)
            page = context.new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url)
            page.wait_for_function("() => !document.getElementById('lost').hidden", timeout=5000)
            lost = _lost_state(page)
            rates = [_figure(page, RADAR, "rate"), page.text_content('#feeds td[data-counter="rate"]')]
            mode["events"] = "server"
            page.wait_for_function("() => document.getElementById('lost').hidden", timeout=8000)
            live = _lost_state(page)
            stop.set()
            stopped_wall_s = time.time()
            thread.join(5.0)
            page.wait_for_function("() => !document.getElementById('lost').hidden", timeout=8000)
            gone = _lost_state(page)
        finally:
            browser.close()
    assert "Connection to msdc lost" in lost["lost"] and "no snapshot since 08:00:00 UTC" in lost["lost"]
    assert "stale" in lost["lost"] and lost["clock"] == "last update 08:00:00 UTC"
    assert lost["stale"] and lost["opacity"] == pytest.approx(0.45)
    # each rate says the time it was measured over: 45 s of uptime, shorter than the 120 s window
    assert rates == ["2.00 over 45 s", "12.5 over 44 s"]
    assert live["lost"] is None and not live["stale"] and live["opacity"] == 1.0
    assert live["clock"] != "08:00:00 UTC" and live["clock"].endswith(" UTC")
    # lost again once the server stopped: since its last snapshot, made within the 1.5 s before it stopped
    # (a snapshot a second; the clock read to the second)
    said = gone["lost"].split("no snapshot since ")[1][:8]
    last_s = [time.strftime("%H:%M:%S", time.gmtime(stopped_wall_s - d)) for d in (0.0, 1.0, 2.0)]
    assert gone["stale"] and said in last_s and gone["clock"] == f"last update {said} UTC"
    assert errors == []


class FailingAfterFirst(ReplayState):
    """A state whose first snapshot is made, every later one fails."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.calls = 0

    def recent(self, window_s: float):
        self.calls += 1
        if self.calls > 1:
            raise RuntimeError("the state broke")
        return super().recent(window_s)


def test_a_failed_snapshot_greys_the_last_good_figures_and_says_as_of_when() -> None:
    """After a failed snapshot the server sends the last good one again with its error: the page showed
    those figures as current. Now it greys them, its clock and the error say the good snapshot's time, and
    the connection stays live (nothing is lost but the figures' freshness)."""
    sync_playwright = _browser()
    state = FailingAfterFirst(synthetic_measurements(), speed=20.0, start_wall_s=time.time() - 10.0)
    errors: list[str] = []
    with running(state, Thresholds(window_s=30.0)) as (url, _, _), sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_context(viewport={"width": 1200, "height": 720}).new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url)
            page.wait_for_function("() => !document.getElementById('error').hidden", timeout=8000)
            shown = _lost_state(page)
            said = page.text_content("#error")
        finally:
            browser.close()
    assert "snapshot failed" in said and "the state broke" in said
    as_of = said.split("as of ")[1].rstrip(".")
    assert shown["clock"] == f"last update {as_of}" and as_of.endswith(" UTC")
    assert shown["stale"] and shown["opacity"] == pytest.approx(0.45) and shown["lost"] is None
    assert errors == []
