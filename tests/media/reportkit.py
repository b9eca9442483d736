"""Checks of an ``--exe`` grid's ``report.html`` shared by the report's tests (with and without DDS)."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote, urlparse

LINK = re.compile(r'\b(?:href|src|poster)="([^"]*)"')


def page_links(page: Path) -> list[str]:
    """Every link of the page (``href``, ``src``, ``poster``) except anchors within it."""
    return [link for link in LINK.findall(page.read_text(encoding="utf-8")) if link and not link.startswith("#")]


def broken_links(page: Path) -> list[str]:
    """The links that would not work once the page's directory is zipped and opened elsewhere: absolute paths,
    URLs with a scheme (file:, http:) and relative links to nothing."""
    broken = []
    for link in page_links(page):
        parsed = urlparse(link)
        if parsed.scheme or parsed.netloc or link.startswith("/"):
            broken.append(f"{link} (not relative)")
        elif not (page.parent / unquote(parsed.path)).exists():
            broken.append(f"{link} (missing)")
    return broken


def mp4_frames(path: Path) -> tuple[int, tuple[int, int]]:
    """(frames, (width, height)) of an MP4, decoding its first frame to show it is a real video."""
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    first = next(reader)
    reader.close()
    assert len(first) == width * height * 3, "the first frame did not decode to an RGB image"
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(path))
    return frames, (width, height)
