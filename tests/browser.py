"""Headless Chromium for the tests: found on the machine, or installed from Debian's packages."""

import os
import re
import shutil
import subprocess
import tempfile

import pytest

CANDIDATES = ("chromium", "chromium-browser", "google-chrome")


def find_or_install_chromium():
    """Path of a Chromium executable; installs Debian's chromium when missing (root, apt).

    Outside CI a missing browser that cannot be installed skips the test;
    in CI (CI=true) it fails it, so that the check is never silently lost.
    """
    for name in CANDIDATES:
        path = shutil.which(name)
        if path:
            return path
    if shutil.which("apt-get") and os.geteuid() == 0:
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        for command in (["apt-get", "install", "-y", "-q", "chromium"],
                        ["sh", "-c", "apt-get update -q && apt-get install -y -q chromium"]):
            if subprocess.run(command, env=env, capture_output=True).returncode == 0:
                break
        path = shutil.which("chromium")
        if path:
            return path
    message = "headless Chromium is not installed and could not be installed with apt-get"
    if os.environ.get("CI"):
        pytest.fail(message)
    pytest.skip(message)


def load(chromium, page, budget_ms=4000):
    """Open `page` in headless Chromium, let its scripts run, return (DOM, JavaScript errors)."""
    with tempfile.TemporaryDirectory() as profile:
        result = subprocess.run(
            [chromium, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
             f"--virtual-time-budget={budget_ms}", "--dump-dom", page.resolve().as_uri()],
            capture_output=True, text=True, timeout=120)
    dom = result.stdout
    recorded = re.search(r'data-js-errors="([^"]*)"', dom)
    errors = [recorded.group(1)] if recorded else []
    # uncaught exceptions also appear on the console log; resource loads (CDN, offline) do not count
    errors += [line for line in result.stderr.splitlines() if "Uncaught" in line]
    return dom, errors
