"""The printed table and the plot of a tuning report (scripts/tune/tune_replay.py's report.json).

The table groups rows by source, one row per configuration, so that the effect of the swept value on
one estimator reads down a column. The plot has one panel per metric, the configurations along x and one
line per source, so that a trade (detection up, error up, CPU up) is seen at a glance.
"""
import os

import matplotlib

matplotlib.use("Agg")  # headless: written to a file, no display needed
import matplotlib.pyplot as plt  # noqa: E402

SOURCES = ("disparity", "mono_visible", "mono_ir", "fused")
COLUMNS = (  # (header, width)
    ("source", 12), ("configuration", 28), ("detected", 13), ("pos err mm", 13), ("range err mm", 13),
    ("orient err deg", 14), ("diff pos mm", 13), ("diff orient deg", 15), ("flips", 6), ("cpu ms", 12))
NOTE = ("detected: valid estimates / image frames of its camera (fused: of any camera). err: against the "
        "simulator's truth,\nmedian / p95 over the valid estimates. diff: stamp by stamp against the first "
        "configuration, median / p95 where both\nare valid; flips: frames valid in one of the two only. "
        "cpu: processing_time_ms per frame, median / p95 (fused: none of its own).")


def pair(stats, digits=1):
    """'median / p95' of a statistics_of() entry, '-' when nothing was measured."""
    if not stats or stats.get("median") is None:
        return "-"
    return "%.*f / %.*f" % (digits, stats["median"], digits, stats["p95"])


def row_cells(label, source, metrics):
    rate = metrics.get("detection_rate")
    difference = metrics["difference_to_reference"]
    return [source, label,
            "-" if rate is None else "%.0f%% %d/%d" % (100.0 * rate, metrics["valid_frames"], metrics["frames"]),
            pair(metrics.get("position_error_mm")), pair(metrics.get("range_error_mm")),
            pair(metrics.get("orientation_error_deg"), 2), pair(difference["position_mm"]),
            pair(difference["orientation_deg"], 2), str(difference["validity_flips"]),
            pair(metrics.get("cpu_ms"))]


def table(report):
    """The report as fixed-width text: a header, one block of rows per source, and a note."""
    def line(cells):
        return "  ".join(cell[:width].ljust(width) for cell, (_, width) in zip(cells, COLUMNS)).rstrip()

    lines = ["bag: %s (truth: %s; frames: %s)" % (shown_path(report["bag"]), "yes" if report["truth"] else "no",
                                                   ", ".join("%s %d" % kv for kv in report["camera_frames"].items())),
             line([header for header, _ in COLUMNS])]
    for source in SOURCES:
        lines.append("")
        for configuration in report["configurations"]:
            lines.append(line(row_cells(configuration["label"], source, configuration["sources"][source])))
    lines += ["", NOTE]
    return "\n".join(lines)


def shown_path(path):
    """A bag inside the repository by its path there (bags/far_approach.bag), the same on every clone."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    relative = os.path.relpath(path, root)
    return path if relative.startswith("..") else relative


def series(report, source, getter):
    """One source's values across the configurations (None where not measured: a gap in the line)."""
    values = []
    for configuration in report["configurations"]:
        try:
            values.append(getter(configuration["sources"][source]))
        except (KeyError, TypeError):
            values.append(None)
    return values


PANELS = (  # (title, getter of one source's metrics)
    ("detection rate (%)", lambda m: None if m["detection_rate"] is None else 100.0 * m["detection_rate"]),
    ("position error vs truth, median (mm)", lambda m: m["position_error_mm"]["median"]),
    ("position error vs truth, p95 (mm)", lambda m: m["position_error_mm"]["p95"]),
    ("orientation error vs truth, median (deg)", lambda m: m["orientation_error_deg"]["median"]),
    ("position difference to the first, p95 (mm)", lambda m: m["difference_to_reference"]["position_mm"]["p95"]),
    ("CPU per frame, median (ms)", lambda m: m["cpu_ms"]["median"]),
)


def plot(report, path):
    """report.png: one panel per metric, x = configuration, one line per source."""
    labels = [c["label"] for c in report["configurations"]]
    figure, axes = plt.subplots(2, 3, figsize=(15, 8))
    for axis, (title, getter) in zip(axes.flat, PANELS):
        for index, source in enumerate(SOURCES):
            values = series(report, source, getter)
            if any(v is not None for v in values):  # one colour per source in every panel
                axis.plot(range(len(labels)), [float("nan") if v is None else v for v in values], marker="o",
                          color="C%d" % index, label=source)
        axis.set_title(title, fontsize=10)
        axis.set_xticks(range(len(labels)))
        axis.set_xticklabels(labels, rotation=15, fontsize=8)
        axis.set_xlim(-0.3, len(labels) - 0.7)
        axis.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    figure.suptitle("%s%s" % (report["bag"], "" if report["truth"] else " (no truth in the bag)"), fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)
