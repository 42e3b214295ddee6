#!/usr/bin/env python3
"""A QR code as a YUV4MPEG2 video: the fake camera of the browser test of the dashboard's QR
scanning.

Chromium started with --use-fake-device-for-media-stream --use-file-for-fake-video-capture=F.y4m
plays F to getUserMedia instead of a camera, looping at its end. The page decodes what it sees
with jsQR, so the test can show a valve's serial label to the page without a camera. Debian's
qrencode draws the code (its text output, quiet zone of 4 modules, parsed exactly); this module
scales it by a whole factor to fill the height, centres it, black on white, and writes the same
grey frame `frames` times (Y plane, then U and V at 128: no colour).

    qr_video.py TJV000007 serial.y4m
"""

import argparse
import shutil
import subprocess
import sys

MARGIN = 4  # modules of quiet zone around the code, qrencode's default and the standard's


class QrencodeMissing(RuntimeError):
    """qrencode is not installed."""


def qr_modules(text):
    """The code's module rows for `text`, quiet zone included: lists of True for black."""
    program = shutil.which("qrencode")
    if program is None:
        raise QrencodeMissing("qrencode is not installed: apt-get install qrencode "
                              "(Debian package qrencode)")
    # The text goes on stdin, so one starting with '-' is not taken for an option.
    done = subprocess.run([program, "-t", "ASCII", "-m", str(MARGIN), "-o", "-"],
                          input=text.encode(), capture_output=True, check=False)
    if done.returncode != 0:
        raise ValueError(f"qrencode exited {done.returncode}: {done.stderr.decode().strip()}")
    rows = done.stdout.decode("ascii").splitlines()
    # Each module is two characters: "##" black, "  " white.
    matrix = [[row[i:i + 2] == "##" for i in range(0, len(row), 2)] for row in rows]
    if not matrix or any(len(row) != len(matrix) for row in matrix):
        raise ValueError(f"qrencode's output is not a square of modules: {rows!r}")
    return matrix


def write_qr_video(text, path, width=640, height=480, frames=30, fps=10):
    """Write `frames` frames of the QR code of `text` to `path` as YUV4MPEG2 (4:2:0)."""
    if width % 2 or height % 2:
        raise ValueError(f"4:2:0 needs an even width and height, not {width}x{height}")
    matrix = qr_modules(text)
    scale = min(width, height) // len(matrix)
    if scale < 1:
        raise ValueError(f"a {len(matrix)}-module code does not fit in {width}x{height}")
    side = scale * len(matrix)
    left, top = (width - side) // 2, (height - side) // 2
    white_row = b"\xff" * width
    luma = bytearray()
    for y in range(height):
        module_row = (y - top) // scale
        if not 0 <= module_row < len(matrix):
            luma += white_row
            continue
        line = bytearray(white_row)
        for column, black in enumerate(matrix[module_row]):
            if black:
                start = left + column * scale
                line[start:start + scale] = b"\x00" * scale
        luma += line
    chroma = b"\x80" * (width // 2 * (height // 2) * 2)
    frame = b"FRAME\n" + bytes(luma) + chroma
    with open(path, "wb") as video:
        video.write(f"YUV4MPEG2 W{width} H{height} F{fps}:1 Ip A1:1 C420jpeg\n".encode())
        for _ in range(frames):
            video.write(frame)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("text", help="what the code says, e.g. a valve serial")
    parser.add_argument("out", help="the .y4m file to write")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--fps", type=int, default=10)
    args = parser.parse_args()
    try:
        write_qr_video(args.text, args.out, args.width, args.height, args.frames, args.fps)
    except (QrencodeMissing, ValueError) as error:
        print(f"qr_video.py: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
