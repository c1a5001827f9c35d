"""Make ``docs/report_first_page.png``: the first printed page of a calibration report, as the README shows it.

It calibrates a simulated 6-axis sensor (a slightly bent channel, 10 load configurations) with the LTM and
writes the report with a rated capacity, a specification and conditions, exactly with the README's commands:
``ftcal fit ... --report`` and ``chromium --headless ... --print-to-pdf``; then renders the PDF's first page
with poppler's ``pdftoppm`` and stores it as a small palette PNG.

Run from the repository root (needs ``chromium`` and ``pdftoppm``)::

    python docs/report_screenshot.py
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ftcal import CalibrationDataset

OUT = Path(__file__).with_name("report_first_page.png")


def demo_dataset(seed: int = 0) -> CalibrationDataset:
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, size=(240, 6)) * [400, 400, 800, 15, 15, 15]
    gains = rng.normal(size=(6, 6)) / [400, 400, 800, 15, 15, 15]
    raw = wrench @ gains.T + 0.1 + 0.001 * rng.normal(size=(240, 6))
    raw[:, 2] += 0.02 * (wrench[:, 2] / 800) ** 2
    return CalibrationDataset(raw=raw, wrench=wrench, group=np.repeat(np.arange(12), 20),
                              meta={"sensor": "FT-DEMO SN 0042"})


def main() -> None:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if chromium is None or shutil.which("pdftoppm") is None:
        raise SystemExit("needs chromium and pdftoppm (apt-get install chromium poppler-utils)")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        demo_dataset().save(work / "recording.csv")
        (work / "recording.conditions.yaml").write_text(
            "reference_standard: dead weights (OIML class M1) on a loading fixture\n"
            "procedure: 12 load configurations x 20 loads, each axis both signs\n"
            "operator: A. Tester\nambient_temperature: 22.5 °C\nrecalibration_interval: 12 months\n",
            encoding="utf-8")
        subprocess.run([sys.executable, "-m", "ftcal", "fit", str(work / "recording.csv"), "--model", "linear",
                        "--report", "--rated", "Fx=500,Fy=500,Fz=900,Tx=20,Ty=20,Tz=20", "--spec", "1%FS",
                        "--reference-uncertainty", "0.02%",
                        "--out", str(work / "models"), "-q"], check=True)
        pdf = work / "models" / "linear.report.pdf"
        subprocess.run([chromium, "--headless", "--no-sandbox", "--no-pdf-header-footer", "--disable-gpu",
                        f"--user-data-dir={work / 'profile'}", f"--print-to-pdf={pdf}",
                        str(work / "models" / "linear.report.html")], check=True, capture_output=True,
                       stdin=subprocess.DEVNULL)
        subprocess.run(["pdftoppm", "-f", "1", "-l", "1", "-r", "100", "-png", "-singlefile", str(pdf),
                        str(work / "page")], check=True)
        from PIL import Image

        from PIL import ImageOps

        page = Image.open(work / "page.png").convert("RGB")  # A4 at 100 dpi: 827 x 1169
        left, top, right, bottom = ImageOps.invert(page.convert("L")).getbbox()  # the ink (the footer included)
        ink = np.asarray(page.convert("L")) < 250
        rows = np.flatnonzero(ink[:, left:right].any(axis=1))
        body_end = rows[rows < page.height * 0.9].max()  # the summary, without the page footer far below
        box = (max(left - 24, 0), max(top - 24, 0), min(right + 24, page.width), min(body_end + 24, page.height))
        page.crop(box).quantize(colors=64).save(OUT, optimize=True)
    print(f"{OUT} ({OUT.stat().st_size // 1024} KiB; crop {tuple(int(b) for b in box)} of the printed first page)")


if __name__ == "__main__":
    main()
