"""The HTML report in a real browser: headless Chromium opens ``report.html`` and every figure
in it loads and decodes whole.

How: a copy of the page, with a ``<base>`` at the report's folder (its relative figure paths
resolve as in the original) and a script that runs once the page has loaded (every image
loaded or failed) and writes, for each ``<img>``, its natural size (0 x 0: missing, or not an
image the browser can decode) and whether its bottom row of pixels is opaque once drawn on a
canvas (the report's figures have a white background; the rows of a cut-short PNG that never
arrived are transparent, though the browser knows its size from the header). Chromium dumps
the DOM (``--dump-dom``), from which the test reads those numbers. ``--allow-file-access-from-files``
lets the page read back its own figures' pixels from file:// URLs.

Skipped where Chromium is not installed (Debian: ``apt-get install -y chromium``).
"""

import html
import json
import re
import shutil
import struct
import subprocess

import pytest

from drydem.parametric.records import write_record
from drydem.parametric.study import RunSpec
from drydem.report.study import build_report

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="headless Chromium not installed (no `chromium` on PATH; Debian: "
                                "apt-get install -y chromium): the HTML report is not checked in a browser")

#: written into a copy of the page: once every image has loaded or failed, each <img>'s src,
#: natural size and whether its bottom row is opaque (null where it has no pixels)
PROBE = """<script>
window.addEventListener("load", () => {
  const found = Array.from(document.images, (img) => {
    let opaque = null;
    if (img.naturalWidth > 0) {
      const canvas = document.createElement("canvas");
      canvas.width = img.naturalWidth;
      canvas.height = img.naturalHeight;
      const context = canvas.getContext("2d");
      context.drawImage(img, 0, 0);
      const alpha = context.getImageData(0, img.naturalHeight - 1, img.naturalWidth, 1).data.filter((_, k) => k % 4 === 3);
      opaque = alpha.every((a) => a === 255);
    }
    return {src: img.getAttribute("src"), width: img.naturalWidth, height: img.naturalHeight, opaque: opaque};
  });
  const out = document.createElement("pre");
  out.id = "drydem-probe";
  out.textContent = JSON.stringify(found);
  document.body.appendChild(out);
});
</script>"""
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--allow-file-access-from-files",
         "--virtual-time-budget=10000", "--dump-dom"]


def images_in_chromium(page, scratch) -> list[dict]:
    """Each <img> of the HTML file ``page`` as headless Chromium shows it (module docstring):
    src, width and height (natural, px), opaque (its bottom row); ``scratch``: a folder for the
    probed copy and the browser's profile."""
    text = page.read_text(encoding="utf-8")
    probed = scratch / "probed.html"
    probed.write_text(text.replace("<head>", f"<head><base href='{page.parent.as_uri()}/'>", 1).replace("</body>", f"{PROBE}</body>", 1),
                      encoding="utf-8")
    ran = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={scratch / 'profile'}", probed.as_uri()],
                         capture_output=True, text=True, timeout=120)
    found = re.search(r'<pre id="drydem-probe">(.*?)</pre>', ran.stdout, re.S)
    assert found, f"Chromium did not finish loading {page} (exit code {ran.returncode}): {ran.stderr[-2000:]}"
    return json.loads(html.unescape(found.group(1)))


def png_size(path) -> tuple[int, int]:
    """Width and height (px) of a PNG file, from its IHDR chunk (the PNG specification, 11.2.2)."""
    return struct.unpack(">II", path.read_bytes()[16:24])


def figure_problems(page, scratch) -> list[str]:
    """Why each figure of the report ``page`` does not show whole in Chromium: missing or
    undecodable (no pixels), shown at another size than its PNG file's, or cut short (its
    bottom row transparent); [] when every one shows."""
    problems = []
    for image in images_in_chromium(page, scratch):
        path = page.parent / image["src"]
        if image["width"] == 0:
            problems.append(f"{image['src']}: does not load (missing, or not an image)")
        elif path.is_file() and (image["width"], image["height"]) != png_size(path):
            problems.append(f"{image['src']}: shown {image['width']} x {image['height']} px, the file is {png_size(path)}")
        elif not image["opaque"]:
            problems.append(f"{image['src']}: its bottom row is not drawn (cut short)")
    return problems


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """A report with figures of the paper's walls and of a user's target, from made-up records."""
    from test_report import limit_record, tilt_record

    folder = tmp_path_factory.mktemp("study")
    records = [tilt_record(d, kn, protocol=p) for d in ("WD1", "WD3", "WD6") for kn in (3e7, 1e9) for p in ("adaptive", "fixed")]
    mine = tilt_record("WD3", 1e8, protocol="fixed")  # a user's wall file: its own section and figure
    mine["spec"]["target"] = str(folder / "walls" / "mine.toml")
    mine["id"] = RunSpec(**mine["spec"]).id
    for record in [*records, mine, limit_record("WD2", "associative")]:
        write_record(folder, record)
    return build_report(folder)


def test_every_figure_of_the_html_report_shows_in_chromium(report, tmp_path):
    figures = report.markdown.read_text().count("](figures/")
    images = images_in_chromium(report.html, tmp_path)
    assert len(images) == figures == 8  # the paper's 7 figures and the user's target's pushover curves
    assert any("yours" in image["src"] for image in images)
    assert figure_problems(report.html, tmp_path) == []


def test_the_browser_check_finds_a_missing_a_garbled_and_a_cut_short_figure(report, tmp_path):
    copy = tmp_path / "report"
    shutil.copytree(report.html.parent, copy)
    page = copy / "report.html"
    page.write_text(page.read_text().replace("figures/fig03_contact_points.png", "figures/no_such_figure.png"))
    (copy / "figures" / "fig06_stiffness.png").write_bytes(b"not a PNG")
    cut = copy / "figures" / "fig12_dls.png"
    cut.write_bytes(cut.read_bytes()[: cut.stat().st_size // 2])
    assert figure_problems(page, tmp_path) == [
        "figures/no_such_figure.png: does not load (missing, or not an image)",
        "figures/fig06_stiffness.png: does not load (missing, or not an image)",
        "figures/fig12_dls.png: its bottom row is not drawn (cut short)",
    ]
    (tmp_path / "again").mkdir()
    assert figure_problems(report.html, tmp_path / "again") == []  # the original is untouched
