#!/usr/bin/env python3
"""Generates the docking-face texture named in config/target.yaml (deterministic for a seed).

The face gets a feature-rich design (panels, labels, bolts, shapes: corners for BRISK), the docking
port at the centre and the 5 reference markers as dark printed dots at the positions target.yaml
gives, so the texture and the marker model can never disagree if this script is rerun after an edit.

Usage: make_target_texture.py [--target config/target.yaml] [--px-per-m 2000] [--seed 7]
"""
import argparse
import os
import sys

import cv2
import numpy as np
import yaml


def face_to_px(y_m, z_m, width_m, height_m, px_per_m):
    """Column u runs along +y, row v along -z (target.yaml's convention)."""
    u = (y_m + width_m / 2.0) * px_per_m
    v = (height_m / 2.0 - z_m) * px_per_m
    return u, v


def draw_design(img, rng, keep_out):
    h, w = img.shape[:2]
    # Base: a gold MLI-like panel with a coarse diagonal crinkle so the face is not flat-coloured.
    img[:] = (40, 150, 190)
    for _ in range(260):
        x0, y0 = rng.integers(0, w), rng.integers(0, h)
        length = rng.integers(15, 70)
        ang = rng.uniform(0, np.pi)
        x1, y1 = int(x0 + length * np.cos(ang)), int(y0 + length * np.sin(ang))
        shade = int(rng.integers(-45, 45))
        col = tuple(int(np.clip(c + shade, 0, 255)) for c in (40, 150, 190))
        cv2.line(img, (int(x0), int(y0)), (x1, y1), col, int(rng.integers(2, 5)), cv2.LINE_AA)
    # Structured panels: high-contrast rectangles with labels and bolts (good, stable corners).
    palette = [(30, 30, 30), (235, 235, 235), (160, 60, 20), (20, 20, 140), (70, 110, 70), (200, 200, 90)]
    for _ in range(22):
        pw, ph = int(rng.integers(40, 130)), int(rng.integers(25, 90))
        x, y = int(rng.integers(0, w - pw)), int(rng.integers(0, h - ph))
        col = palette[int(rng.integers(len(palette)))]
        cv2.rectangle(img, (x, y), (x + pw, y + ph), col, -1)
        inner = palette[int(rng.integers(len(palette)))]
        if inner != col:
            cv2.rectangle(img, (x + 5, y + 5), (x + pw - 5, y + ph - 5), inner, 2)
        text = "".join(chr(int(c)) for c in rng.integers(65, 91, size=int(rng.integers(2, 5))))
        tcol = (0, 0, 0) if sum(col) > 380 else (255, 255, 255)
        cv2.putText(img, text, (x + 8, y + ph // 2 + 8), cv2.FONT_HERSHEY_SIMPLEX, 0.6, tcol, 2, cv2.LINE_AA)
        for bx, by in ((x + 4, y + 4), (x + pw - 4, y + 4), (x + 4, y + ph - 4), (x + pw - 4, y + ph - 4)):
            cv2.circle(img, (bx, by), 2, (90, 90, 90), -1, cv2.LINE_AA)
    for _ in range(30):
        c = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        pts = np.array([[c[0] + rng.integers(-25, 25), c[1] + rng.integers(-25, 25)] for _ in range(3)], np.int32)
        cv2.fillPoly(img, [pts], palette[int(rng.integers(len(palette)))], cv2.LINE_AA)
    # Clear white pads where the markers and the port go, so the dots keep their contrast.
    for (u, v, r) in keep_out:
        cv2.circle(img, (int(round(u)), int(round(v))), int(r), (245, 245, 245), -1, cv2.LINE_AA)
    # Frame around the face edge.
    cv2.rectangle(img, (0, 0), (w - 1, h - 1), (25, 25, 25), 6)


def draw_circle_subpixel(img, u, v, r, color):
    """Filled antialiased circle at a sub-pixel centre (pixel centres at integer coordinates)."""
    shift = 4
    s = 1 << shift
    cv2.circle(img, (int(round(u * s)), int(round(v * s))), int(round(r * s)), color, -1, cv2.LINE_AA, shift)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default_target = os.path.normpath(os.path.join(here, "..", "..", "..", "config", "target.yaml"))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", default=default_target)
    ap.add_argument("--px-per-m", type=float, default=2000.0)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()

    with open(args.target) as f:
        model = yaml.safe_load(f)["target"]
    face = model["face"]
    width_m, height_m = float(face["width_m"]), float(face["height_m"])
    w, h = int(round(width_m * args.px_per_m)), int(round(height_m * args.px_per_m))
    ppm = args.px_per_m
    out_path = os.path.join(os.path.dirname(args.target), face["texture"])

    markers = [face_to_px(float(m[1]), float(m[2]), width_m, height_m, ppm) for m in model["markers_m"]]
    marker_r = float(model["marker_radius_m"]) * ppm
    port_r = float(model["port_radius_m"]) * ppm
    port_u, port_v = face_to_px(0.0, 0.0, width_m, height_m, ppm)
    keep_out = [(u, v, marker_r * 1.8) for (u, v) in markers] + [(port_u, port_v, port_r * 1.35)]

    rng = np.random.default_rng(args.seed)
    img = np.zeros((h, w, 3), np.uint8)
    draw_design(img, rng, keep_out)

    # Docking port: a dark recess with a bright rim and a cross-hair (texture pixel centres are at
    # integer + 0.5 in face coordinates, hence the -0.5).
    draw_circle_subpixel(img, port_u - 0.5, port_v - 0.5, port_r, (60, 60, 60))
    draw_circle_subpixel(img, port_u - 0.5, port_v - 0.5, port_r * 0.8, (20, 20, 20))
    cv2.line(img, (int(port_u - port_r * 0.6), int(port_v)), (int(port_u + port_r * 0.6), int(port_v)), (200, 200, 200), 2)
    cv2.line(img, (int(port_u), int(port_v - port_r * 0.6)), (int(port_u), int(port_v + port_r * 0.6)), (200, 200, 200), 2)
    # Reference markers: dark dots.
    for (u, v) in markers:
        draw_circle_subpixel(img, u - 0.5, v - 0.5, marker_r, (15, 15, 15))

    os.makedirs(os.path.dirname(out_path), exist_ok=True)
    cv2.imwrite(out_path, img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print("wrote %s (%dx%d px, %.0f px/m, %d bytes)" % (out_path, w, h, ppm, os.path.getsize(out_path)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
