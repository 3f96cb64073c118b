"""The live monitor page in a real headless Chromium (Debian's, through Playwright) with every request not to
the monitor refused: the fixture recording replayed 20x through a fake live state appears on the map within
2 s, its counters move, the radar's silent alarm is raised when its replay stops, nothing logs an error, and
a page that goes away leaves the server serving the next one."""

from __future__ import annotations

import os
import shutil
import time

import pytest
from live_fake_state import ReplayState, fixture_measurements, running

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
