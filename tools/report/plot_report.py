#!/usr/bin/env python3
"""Draws the plots of an `ecrf report` directory from the CSV files the C++ side writes.

  plot_report.py REPORT_DIR
      Reads rd.csv, anchors.csv, chunks.csv, curve.csv and speed.csv in REPORT_DIR (the scene
      name from report.json) and writes rd.png, ratio.png, chunks.png, curve.png and speed.png
      beside them: each plot whose CSV exists and has rows.
      cost.png (speed against error: PSNR against work per pixel and render time) needs rd.csv's
      head, work_per_pixel and seconds_per_view columns (reports from before them have none).
  plot_report.py --compare OUT.png COMPARE_CSV
      Draws the rate-distortion curves of COMPARE_CSV (series,file_bytes,psnr,left_out,
      work_per_pixel,seconds_per_view) into OUT.png, and their speed against error into
      OUT_cost.png when the points' costs are known.

Prints one line per PNG written; each is written to a temporary file in its directory and renamed
into place. Empty CSV cells mean "not available". Exit status: 0 done (a plot without data is
skipped), 1 a malformed CSV (the other plots are still drawn) or a PNG that could not be written,
2 usage, 3 matplotlib missing. Needs the standard library and matplotlib (python3-matplotlib).
"""
import csv
import io
import json
import math
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker
except ImportError:
    plt = None

NO_MATPLOTLIB = ("plot_report.py: matplotlib is not installed (apt-get install python3-matplotlib); "
                 "the report's tables and CSV files are complete without the plots")
MARKERS = "osD^vPX<>"
ANCHOR_STYLES = [("s", "tab:red"), ("D", "tab:purple"), ("^", "tab:brown"), ("v", "tab:olive"),
                 ("P", "tab:cyan"), ("X", "tab:pink")]
BYTES_AXIS = "file size (log scale; 1 KB = 1000 bytes)"


class CsvError(Exception):
    pass


def read_csv(path, columns, optional=False):
    """The rows of path as dicts; [] when the file is missing or has no rows, or (optional) lacks
    one of `columns`. `columns` are the columns used ('#': a number, read as a float or None when
    empty); others are ignored."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        return []
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise CsvError(f"{path}:{line}: not UTF-8 text ({e.reason})") from None
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    rows, header = [], None
    try:
        for fields in reader:
            where = f"{path}:{reader.line_num}"
            if header is None:
                header = fields
                missing = [c.rstrip("#") for c in columns if c.rstrip("#") not in header]
                if missing and optional:
                    return []
                if missing:
                    raise CsvError(f"{where}: the header lacks column(s) {', '.join(missing)}")
            elif len(fields) != len(header) and fields:
                raise CsvError(f"{where}: {len(fields)} field(s), the header has {len(header)}")
            elif fields:
                row = dict(zip(header, fields))
                for c in (c[:-1] for c in columns if c.endswith("#")):
                    row[c] = number(row[c], f"{where}: column {c}")
                rows.append(row)
    except csv.Error as e:
        raise CsvError(f"{path}:{reader.line_num}: {e}") from None
    return rows


def number(text, where):
    if not text.strip():
        return None
    try:
        value = float(text)
    except ValueError:
        raise CsvError(f"{where}: {text!r} is not a number") from None
    return value if math.isfinite(value) else None  # nan/inf cannot be placed: as good as missing


def positive(v):
    return v is not None and v > 0  # what a log axis can show


def bytes_text(b, digits=3):
    for unit, scale in (("MB", 1e6), ("KB", 1e3)):
        if b >= (1 - 0.5 * 10 ** -digits) * scale:  # 999.9 KB reads "1 MB", not "1e+03 KB"
            return f"{b / scale:.{digits}g} {unit}"
    return f"{b:.0f} B"


def new_axes(title, xlabel, ylabel):
    fig, ax = plt.subplots(figsize=(8, 5), dpi=110, layout="constrained")
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.grid(True, alpha=0.35)
    return fig, ax


def log_x(ax, fmt):
    """Log x axis labelled by fmt(value, significant digits), set once everything is plotted:
    powers of ten alone leave one or two labels on the usual one or two decades, so 1-2-5 (or 1-3)
    steps where they fit; points close together get linear ticks, told apart by more digits."""
    ax.set_xscale("log")
    lo, hi = ax.get_xlim()
    decades = math.log10(hi / lo)
    subs = (1, 2, 5) if decades <= 2.5 else (1, 3) if decades <= 5 else (1,)
    ax.xaxis.set_major_locator(ticker.LogLocator(base=10, subs=subs))
    ticks = [t for t in ax.xaxis.get_major_locator()() if lo <= t <= hi]
    digits = next((d for d in range(3, 8) if len({fmt(t, d) for t in ticks}) == len(ticks)), 8)
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: fmt(v, digits)))
    ax.xaxis.set_minor_formatter(ticker.NullFormatter())


def overlap(a, b):
    w, h = min(a[2], b[2]) - max(a[0], b[0]), min(a[3], b[3]) - max(a[1], b[1])
    return w * h if w > 0 and h > 0 else 0.0


def extent(artist):
    b = artist.get_window_extent(artist.figure.canvas.get_renderer())
    return (b.x0, b.y0, b.x1, b.y1)


def drawn_boxes(ax):
    """Pixel boxes around every marker and along every line of ax: what legends and labels must
    not hide."""
    ax.figure.canvas.draw()  # settles layout and limits, so pixel positions are final
    boxes = []
    for line in ax.get_lines():
        v = line.get_transform().transform_path(line.get_path()).vertices
        if line.get_marker() not in (None, "None", "", " "):
            r = max(3.0, line.get_markersize() * ax.figure.dpi / 144)
            boxes += [(x - r, y - r, x + r, y + r) for x, y in v]
        if line.get_linestyle() not in ("None", "", " "):
            for (x0, y0), (x1, y1) in zip(v, v[1:]):
                n = int(math.hypot(x1 - x0, y1 - y0) / 4) + 1
                for x, y in ((x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n) for k in range(n + 1)):
                    boxes.append((x - 2, y - 2, x + 2, y + 2))
    return boxes


def place_legend(ax, below=False, **kwargs):
    """The legend in a corner of the axes where it hides no point or line, else right of the axes
    (or below them, for legends whose long labels would squeeze the axes; constrained layout makes
    room). loc='best' would ignore the labels placed afterwards."""
    boxes = drawn_boxes(ax)
    for loc in ("upper left", "lower right", "upper right", "lower left", "center right", "center left"):
        if not any(overlap(extent(ax.legend(loc=loc, **kwargs)), b) for b in boxes):
            return
    if below:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), borderaxespad=0, **kwargs)
    else:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), borderaxespad=0, **kwargs)


def place_labels(ax, labels, fontsize=8):
    """Annotates each (x, y, text, color) at the offset that hides the least of the points, lines,
    legend and earlier labels: points cluster (settings near the default), and one fixed offset
    would pile the texts up."""
    taken, frame = drawn_boxes(ax) + [extent(ax.get_legend())], extent(ax)
    offsets = [(5, 4, "left"), (5, -12, "left"), (-5, 4, "right"), (-5, -12, "right"), (0, 8, "center"),
               (0, -17, "center"), (8, -4, "left"), (-8, -4, "right"), (12, 12, "left"), (-12, -20, "right")]
    for x, y, text, color in labels:
        best = None
        for dx, dy, ha in offsets:
            # The white backing keeps a label readable where another series' line crosses it.
            ann = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", ha=ha, color=color,
                              fontsize=fontsize, bbox=dict(boxstyle="square,pad=0.1", fc="white", ec="none",
                                                           alpha=0.75))
            ann.set_in_layout(False)
            box = extent(ann)
            area = (box[2] - box[0]) * (box[3] - box[1])
            cost = sum(overlap(box, t) for t in taken) + 10 * (area - overlap(box, frame))
            if best is None or cost < best[0]:
                if best:
                    best[1].remove()
                best = (cost, ann, box)
            else:
                ann.remove()
        taken.append(best[2])


def draw_anchors(ax, anchors, xkey, ykey):
    rows = [a for a in anchors if positive(a[xkey]) and a[ykey] is not None]
    for a, (marker, color) in zip(rows, ANCHOR_STYLES * len(rows)):
        ax.plot([a[xkey]], [a[ykey]], marker, color=color, markersize=9, label=a["label"])


def plot_rd(scene, rd, anchors):
    points = sorted((r for r in rd if positive(r["file_bytes"]) and r["decoded_psnr"] is not None),
                    key=lambda r: r["file_bytes"])
    if not points:
        return None
    fig, ax = new_axes(f"{scene}: rate–distortion (test PSNR against file size)", BYTES_AXIS, "test PSNR (dB)")
    ax.plot([r["file_bytes"] for r in points], [r["decoded_psnr"] for r in points], "o-", color="tab:blue",
            label="decoded file", zorder=3)
    floats = [r for r in points if r["float_psnr"] is not None]
    for r in floats:  # the quantization loss of the point
        ax.plot([r["file_bytes"]] * 2, [r["float_psnr"], r["decoded_psnr"]], color="tab:blue", lw=0.8, alpha=0.6)
    if floats:
        ax.plot([r["file_bytes"] for r in floats], [r["float_psnr"] for r in floats], "o", markerfacecolor="none",
                color="tab:blue", markersize=8, label="float model (before quantization)")
    reference = [r["float_psnr"] for r in rd if r["lambda_e"] == 0 and r["float_psnr"] is not None]
    # A sweep without a lambda = 0 point borrows the reference: decoded PSNR minus loss gives it back.
    reference += [r["decoded_psnr"] - r["psnr_loss_db"] for r in rd
                  if r["decoded_psnr"] is not None and r["psnr_loss_db"] is not None]
    if reference:
        ax.axhline(reference[0], linestyle="--", color="0.4", lw=1, label=f"λ=0 float model ({reference[0]:.2f} dB)")
    draw_anchors(ax, anchors, "file_bytes", "psnr")
    log_x(ax, bytes_text)
    place_legend(ax)
    place_labels(ax, [(r["file_bytes"], r["decoded_psnr"], lambda_text(r), "tab:blue") for r in points])
    return fig


def lambda_text(r):
    if r.get("label"):
        return r["label"].replace("lambda=", "λ=")
    return "λ=?" if r["lambda_e"] is None else f"λ={r['lambda_e']:g}"


def plot_ratio(scene, rd, anchors):
    points = sorted((r for r in rd if positive(r["ratio"]) and r["psnr_loss_db"] is not None),
                    key=lambda r: r["ratio"])
    if not points:
        return None
    fig, ax = new_axes(f"{scene}: compression ratio against PSNR change (vs the λ=0 float32 model)",
                       "compression ratio (float32 model bytes / file bytes, log scale)",
                       "PSNR change (dB; negative = loss)")
    ax.axhline(0, color="0.4", lw=1, linestyle="--", label="λ=0 float32 model")
    ax.plot([r["ratio"] for r in points], [r["psnr_loss_db"] for r in points], "o-", color="tab:blue",
            label="this report (decoded file)", zorder=3)
    draw_anchors(ax, anchors, "ratio", "psnr_loss_db")
    log_x(ax, lambda v, digits: f"{v:.{digits}g}×")
    place_legend(ax)
    place_labels(ax, [(r["ratio"], r["psnr_loss_db"], lambda_text(r), "tab:blue") for r in points])
    return fig


def chunk_color(name, spare):
    """Colour families by kind of chunk (density blues, appearance reds/oranges), the same in every
    report; chunks this script does not know take the next spare colour."""
    shades = {("density", "plane"): ("Blues", 0.95, 0.85, 0.75), ("density", "line"): ("Blues", 0.6, 0.5, 0.4),
              ("appearance", "plane"): ("Reds", 0.9, 0.75, 0.6), ("appearance", "line"): ("Oranges", 0.7, 0.55, 0.4)}
    parts = name.split(".")
    if len(parts) == 3 and tuple(parts[:2]) in shades and parts[2] in "012":
        cmap, *levels = shades[tuple(parts[:2])]
        return plt.get_cmap(cmap)(levels[int(parts[2])])
    fixed = {"MLPW": "tab:green", "OCCU": "tab:purple", "HEAD": "0.25", "meta": "0.5", "container": "0.75"}
    return fixed.get(name) or next(spare)


def plot_chunks(scene, rows):
    sizes = {}  # point label -> chunk -> bytes, both in the order first seen
    for r in rows:
        chunks = sizes.setdefault(r["label"], {})
        chunks[r["chunk"]] = chunks.get(r["chunk"], 0) + (r["bytes"] or 0)
    if not sizes:
        return None
    canonical = [f"{f}.{k}.{i}" for f in ("density", "appearance") for k in ("plane", "line") for i in range(3)]
    canonical += ["MLPW", "OCCU", "HEAD", "meta", "container"]
    seen = list(dict.fromkeys(r["chunk"] for r in rows))
    # Zero-byte chunks (no occupancy grid, say) would only clutter the legend.
    order = [c for c in dict.fromkeys(canonical + seen) if c in seen and any(s.get(c, 0) > 0 for s in sizes.values())]
    fig, ax = new_axes(f"{scene}: bytes per chunk of each rate point", "rate point", "size (KB, 1 KB = 1000 bytes)")
    ax.grid(False, axis="x")
    labels, bottom = list(sizes), [0.0] * len(sizes)
    spare = iter(["tab:brown", "tab:pink", "tab:olive", "tab:cyan"] * len(order))
    for c in order:
        kb = [sizes[label].get(c, 0) / 1e3 for label in labels]
        ax.bar(range(len(labels)), kb, 0.6, bottom=bottom, color=chunk_color(c, spare), label=c, edgecolor="white",
               linewidth=0.3)
        bottom = [b + k for b, k in zip(bottom, kb)]
    for i, total in enumerate(bottom):
        ax.annotate(bytes_text(total * 1e3), (i, total), xytext=(0, 3), textcoords="offset points", ha="center",
                    fontsize=8)
    crowded = sum(map(len, labels)) > 45  # level tick labels would run into each other
    ax.set_xticks(range(len(labels)), labels, rotation=25 if crowded else 0, ha="right" if crowded else "center")
    ax.set_ylim(0, max(bottom) * 1.08 or 1)
    handles, names = ax.get_legend_handles_labels()
    # Reversed, so that the legend reads top to bottom like the stacks; outside, as bars fill the axes.
    ax.legend(handles[::-1], names[::-1], loc="upper left", bbox_to_anchor=(1.01, 1), borderaxespad=0, fontsize=8)
    return fig


def plot_lines(title, xlabel, curves):
    """One line with markers per (label, [(x, y), ...]) item of curves."""
    fig, ax = new_axes(title, xlabel, "test PSNR (dB)")
    for i, (label, pts) in enumerate(curves.items()):
        ax.plot(*zip(*sorted(pts)), marker=MARKERS[i % len(MARKERS)], markersize=5, label=label)
    return fig, ax


def plot_curve(scene, rows):
    curves = {}
    for r in rows:
        if r["minutes"] is not None and r["test_psnr"] is not None:
            curves.setdefault(r["label"], []).append((r["minutes"], r["test_psnr"]))
    if not curves:
        return None
    fig, ax = plot_lines(f"{scene}: training curves (test PSNR against wall-clock training time)",
                         "training time (minutes)", curves)
    place_legend(ax)
    return fig


def plot_compare(rows):
    # The line joins each curve's Pareto front (what BD-rate integrates); points their own curve
    # beats (left_out = 1) are drawn hollow in the curve's colour, off the line.
    curves, left_out = {}, {}
    for r in rows:
        if positive(r["file_bytes"]) and r["psnr"] is not None:
            target = left_out if r["left_out"] else curves
            target.setdefault(r["series"], []).append((r["file_bytes"], r["psnr"]))
    if not curves:
        return None
    fig, ax = plot_lines("rate–distortion comparison", BYTES_AXIS, curves)
    for line, series in zip(ax.get_lines(), curves):
        if series in left_out:
            ax.plot(*zip(*sorted(left_out[series])), linestyle="none", marker=line.get_marker(),
                    markersize=6, markerfacecolor="none", color=line.get_color(),
                    label=f"{series.split(':')[0]}: left out (a point of its own curve is better)")
    log_x(ax, bytes_text)
    place_legend(ax, below=True)
    return fig


def plot_speed(scene, rows):
    rows = [r for r in rows if positive(r["seconds_per_view"]) and r["psnr"] is not None]
    if not rows:
        return None
    fig, ax = new_axes(f"{scene}: renderer speed against error (one knob moved at a time)",
                       "time per view (seconds, log scale)", "test PSNR (dB)")
    knobs, labels = {}, []
    for r in rows:
        knobs.setdefault(r["knob"], []).append(r)
    # A knob with only the default row (the "default" group) is the star alone.
    for i, (knob, pts) in enumerate((k, p) for k, p in knobs.items() if any(not r["is_default"] for r in p)):
        default = [r["setting"] for r in pts if r["is_default"]]
        ax.plot([r["seconds_per_view"] for r in pts], [r["psnr"] for r in pts], marker=MARKERS[i % len(MARKERS)],
                color=f"C{i % 10}", label=f"{knob} (default {default[0]})" if default else knob)
        labels += [(r["seconds_per_view"], r["psnr"], r["setting"], f"C{i % 10}") for r in pts if not r["is_default"]]
    default = next((r for r in rows if r["is_default"]), None)
    if default:
        ax.plot([default["seconds_per_view"]], [default["psnr"]], "*", color="black", markersize=16, label="default",
                zorder=4)
    log_x(ax, lambda v, digits: f"{v:.{digits}g}")
    place_legend(ax, fontsize=8)
    place_labels(ax, labels, fontsize=7)
    return fig


def cost_panels(title, series):
    """PSNR against work per pixel and against render time, one marker style per series; series:
    {name: [(work_per_pixel, seconds_per_view, psnr, label)]}. None when no point has a cost."""
    if not any(positive(w) for pts in series.values() for w, _, _, _ in pts):
        return None
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), dpi=110, layout="constrained", sharey=True)
    fig.suptitle(title)
    axes[0].set_ylabel("test PSNR (dB)")
    for k, (ax, xlabel) in enumerate(zip(axes, ("work per pixel (decoder units, log scale)",
                                                "render time per view (seconds, log scale)"))):
        ax.set(xlabel=xlabel)
        ax.grid(True, alpha=0.35)
        labels = []
        for i, (name, pts) in enumerate(series.items()):
            pts = [(p[k], p[2], p[3]) for p in pts if positive(p[k]) and p[2] is not None]
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], MARKERS[i % len(MARKERS)], color=f"C{i % 10}",
                        linestyle="none", markersize=8, label=name)
                labels += [(x, y, text, f"C{i % 10}") for x, y, text in pts]
        if labels:
            log_x(ax, (lambda v, digits: f"{v / 1e3:.{digits}g} k") if k == 0 else
                  (lambda v, digits: f"{v:.{digits}g}"))
            ax.margins(x=0.08, y=0.08)
            place_legend(ax, below=True, fontsize=8)  # a corner hiding no point, else below
            place_labels(ax, labels, fontsize=7)
    return fig


def plot_cost(scene, rows):
    series = {}
    for r in rows:
        spacing = "" if r["step_ratio"] in (None, 0.5) else f", {r['step_ratio']:g}-cell spacing"
        series.setdefault(f"{r['head'] or 'mlp'} head{spacing}", []).append(
            (r["work_per_pixel"], r["seconds_per_view"], r["decoded_psnr"], bytes_text(r["file_bytes"] or 0)))
    return cost_panels(f"{scene}: speed against error of the decoded files (label: file size)", series)


def plot_compare_cost(rows):
    series = {}
    for r in rows:
        series.setdefault(r["series"], []).append(
            (r["work_per_pixel"], r["seconds_per_view"], r["psnr"], bytes_text(r["file_bytes"] or 0)))
    return cost_panels("speed against error (label: file size)", series)


def save(fig, path):
    """Writes fig (None: nothing to plot) through a temporary file: a reader never sees half a PNG."""
    if fig is None:
        return
    tmp = os.path.join(os.path.dirname(path) or ".", f".{os.path.basename(path)}.{os.getpid()}.tmp")
    try:
        # tight: long rotated tick labels (a sweep's point names) stay inside the picture.
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
        os.replace(tmp, path)
    except OSError as e:
        raise OSError(f"cannot write {path}: {e.strerror or e}") from None
    finally:
        plt.close(fig)
        if os.path.exists(tmp):
            os.remove(tmp)
    print(path)


def scene_name(d):
    try:
        with open(os.path.join(d, "report.json"), encoding="utf-8") as f:
            scene = json.load(f).get("scene")
        if isinstance(scene, str) and scene:
            return scene
    except (OSError, ValueError, AttributeError):
        pass  # report.json is optional here: the directory's name will do
    return os.path.basename(os.path.abspath(d))


COLUMNS = {
    "rd.csv": ["label", "lambda_e#", "file_bytes#", "decoded_psnr#", "float_psnr#", "ratio#", "psnr_loss_db#"],
    "anchors.csv": ["label", "file_bytes#", "psnr#", "ratio#", "psnr_loss_db#"],
    "chunks.csv": ["label", "chunk", "bytes#"],
    "curve.csv": ["label", "minutes#", "test_psnr#"],
    "speed.csv": ["knob", "setting", "is_default#", "seconds_per_view#", "psnr#"],
    "compare": ["series", "file_bytes#", "psnr#", "left_out#", "work_per_pixel#", "seconds_per_view#"],
    "cost": ["head", "step_ratio#", "file_bytes#", "decoded_psnr#", "work_per_pixel#", "seconds_per_view#"],
}
FILES = {"cost": "rd.csv"}  # tables read from another table's file
OPTIONAL = {"cost"}  # tables whose columns older reports lack
PLOTS = [("rd.png", plot_rd, ["rd.csv", "anchors.csv"]), ("ratio.png", plot_ratio, ["rd.csv", "anchors.csv"]),
         ("chunks.png", plot_chunks, ["chunks.csv"]), ("curve.png", plot_curve, ["curve.csv"]),
         ("speed.png", plot_speed, ["speed.csv"]), ("cost.png", plot_cost, ["cost"])]


def plot_report(d):
    """Draws every plot whose CSV files are sound; False when one was malformed (said on stderr):
    one bad file should not cost the other plots."""
    scene, errors = scene_name(d), []
    for png, draw, names in PLOTS:
        try:
            tables = [read_csv(os.path.join(d, FILES.get(name, name)), COLUMNS[name], name in OPTIONAL)
                      for name in names]
        except CsvError as e:
            if str(e) not in errors:  # rd.csv and anchors.csv feed two plots each
                print(f"plot_report.py: malformed CSV: {e}", file=sys.stderr)
                errors.append(str(e))
            continue
        save(draw(scene, *tables), os.path.join(d, png))
    return not errors


def main(args):
    if args in (["-h"], ["--help"]):
        print(__doc__.strip())
        return 0
    if not (len(args) == 1 and not args[0].startswith("-") or len(args) == 3 and args[0] == "--compare"):
        print("usage: plot_report.py REPORT_DIR | plot_report.py --compare OUT.png COMPARE_CSV", file=sys.stderr)
        return 2
    if plt is None:
        print(NO_MATPLOTLIB, file=sys.stderr)
        return 3
    plt.rcParams.update({"font.size": 11, "axes.titlesize": 11.5, "legend.fontsize": 9})
    try:
        if args[0] != "--compare":
            if not os.path.isdir(args[0]):
                print(f"plot_report.py: {args[0]} is not a directory", file=sys.stderr)
                return 2
            return 0 if plot_report(args[0]) else 1
        rows = read_csv(args[2], COLUMNS["compare"])
        fig = plot_compare(rows)
        if fig is None:
            print(f"plot_report.py: {args[2]} has no points; {args[1]} not drawn", file=sys.stderr)
        save(fig, args[1])
        save(plot_compare_cost(rows), os.path.splitext(args[1])[0] + "_cost.png")
    except CsvError as e:
        print(f"plot_report.py: malformed CSV: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"plot_report.py: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
