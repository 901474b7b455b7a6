#!/usr/bin/env bash
# Soak test: runs N random valid jobs (stream or path surfaces of the analytic fields that
# `orthofront fields` lists, with a random seed inside the field's domain, --edge, --steps,
# --memory and engine options) against an orthofront binary, each under a time cap, and checks
# every one: no crash, no sanitizer report, and a valid mesh read back from the written file.
#
#   tools/soak.sh [BINARY] [-n JOBS] [-t SECONDS] [-s SEED] [-k]
#   ORTHOFRONT=build-asan/apps/orthofront SOAK_JOBS=50 tools/soak.sh
#
# BINARY (or $ORTHOFRONT): the binary to test (default build/apps/orthofront), e.g. an
# AddressSanitizer build. -n/$SOAK_JOBS: number of jobs (200). -t/$SOAK_TIMEOUT: seconds a job
# may run before it counts as hung (60); each job is also given --time-budget of a quarter of it,
# so a merely large job stops cleanly first. -s/$SOAK_SEED: random seed (default: from the clock;
# printed, rerun with it to get the same jobs). -k/$SOAK_KEEP=1: keep the work folder
# ($SOAK_DIR, default a new temporary folder).
#
# A job passes when it exits 0 with a valid mesh and report, or exits 2 with an
# "orthofront: error:" message (a refused job, or a path surface cut short by its budgets, whose
# partial mesh must then be valid too). Anything else fails: another exit status (a signal, the
# time cap, 3 for an unexpected error), a sanitizer report on stderr, a temporary file left
# behind, or a mesh that does not read back as a valid surface (non-finite positions, a face with
# an index out of range or repeated, an edge shared by more than two faces, counts that differ
# from the report, non-manifold edges or degenerate faces in the report's quality figures;
# degenerate faces of the timeline baseline only with $SOAK_STRICT=1). Folds are quality, not
# validity: they are counted on each job's line.
# Prints one line per failure with its command line, and a summary; exit status 1 on failures.
set -u

here=$(cd "$(dirname "$0")" && pwd)
binary=${ORTHOFRONT:-}
jobs=${SOAK_JOBS:-200}
cap=${SOAK_TIMEOUT:-60}
seed=${SOAK_SEED:-}
keep=${SOAK_KEEP:-0}
strict=${SOAK_STRICT:-0}
while [ $# -gt 0 ]; do
  case $1 in
    -n) jobs=$2; shift 2 ;;
    -t) cap=$2; shift 2 ;;
    -s) seed=$2; shift 2 ;;
    -k) keep=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) echo "soak: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) binary=$1; shift ;;
  esac
done
[ -n "$binary" ] || binary="$here/../build/apps/orthofront"
if [ ! -x "$binary" ]; then
  echo "soak: '$binary' is not an executable orthofront binary" >&2
  exit 2
fi
case $jobs in ''|*[!0-9]*) echo "soak: -n '$jobs' is not a number" >&2; exit 2 ;; esac
case $cap in ''|*[!0-9]*) echo "soak: -t '$cap' is not a number of seconds" >&2; exit 2 ;; esac
[ -n "$seed" ] || seed=$(date +%s)
python=$(command -v python3) || { echo "soak: needs python3 (standard library only)" >&2; exit 2; }

work=${SOAK_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/orthofront-soak.XXXXXX")}
mkdir -p "$work"
if [ "$keep" != 1 ] && [ -z "${SOAK_DIR:-}" ]; then trap 'rm -rf "$work"' EXIT; fi

# The job generator and the mesh checker (standard library only, so it runs anywhere python3 does;
# it reads the files itself rather than through orthofront's readers).
helper="$work/soak_helper.py"
cat > "$helper" <<'PY'
import base64, json, math, random, re, struct, sys
import xml.etree.ElementTree as ET

def parse_fields(text):
    """(name, steady, formula+domain text, parameters) per field of `orthofront fields`."""
    fields, steady, cur = [], True, None
    for line in text.splitlines():
        if line.startswith("Unsteady fields"):
            steady = False
            continue
        if line and not line.startswith(" ") and not line.startswith("Parameters"):
            cur = {"name": line.strip(), "steady": steady, "text": "", "domain": "", "params": {}}
            fields.append(cur)
        elif cur is not None and line.startswith("  "):
            s = line.strip()
            cur["text"] += " " + s
            if s.startswith("domain:"):
                cur["domain"] = s[len("domain:"):].strip()
            m = re.match(r"^([A-Za-z_]\w*) = (-?[\d.eE+-]+)\s", s + " ")
            if m and not s.startswith("domain"):
                cur["params"][m.group(1)] = float(m.group(2))
    return fields

def evaluate(expr, names):
    expr = expr.strip().replace("^", "**")
    expr = re.sub(r"(\d)\s*([A-Za-z_(])", r"\1*\2", expr)  # 2pi, -3L
    return float(eval(expr, {"__builtins__": {}}, dict(names, pi=math.pi, sqrt=math.sqrt)))

def domain_box(field):
    """The axis intervals of a field's domain line; symbols (L, x_s) from its own text."""
    names = dict(field["params"])
    for _ in range(3):  # definitions like "L = m/u" and "x_s = 0.989898", in any order
        for sym, expr in re.findall(r"\b([A-Za-z_]\w*) = ([\w.*/+-]+)", field["text"]):
            try:
                names.setdefault(sym, evaluate(expr, names))
            except Exception:
                pass
    box = []
    # Remarks in parentheses ("(three periods per axis)", "([-4,4]^2 for dim=2)") are not axes.
    domain = re.sub(r"\([^()]*\)", "", field["domain"])
    for m in re.finditer(r"\[([^\],]+),([^\]]+)\](\^(\d))?", domain):
        lo, hi = evaluate(m.group(1), names), evaluate(m.group(2), names)
        box += [(lo, hi)] * (int(m.group(4)) if m.group(4) else 1)
    if len(box) not in (2, 3) or any(not lo < hi for lo, hi in box):
        raise ValueError("cannot read the domain of %s: %r" % (field["name"], field["domain"]))
    return box

def point_inside(rng, box, margin):
    return [rng.uniform(lo + margin * (hi - lo), hi - margin * (hi - lo)) for lo, hi in box]

def fmt(values):
    return ",".join("%.6g" % v for v in values)

def make_seed(rng, box, dims):
    """A seed curve inside `box` (2D flows: z = 0)."""
    full = box + [(0.0, 0.0)] * (3 - len(box))
    kind = rng.choice(["line", "line", "line", "circle", "arc"])
    if kind == "line":
        a, b = point_inside(rng, full, 0.1), point_inside(rng, full, 0.1)
        if dims == 2:
            a[2] = b[2] = 0.0
        return "line:%s:%s" % (fmt(a), fmt(b))
    extent = min(hi - lo for lo, hi in box)
    r = rng.uniform(0.03, 0.15) * extent
    c = point_inside(rng, full, 0.0)
    for i, (lo, hi) in enumerate(box):  # keep the circle inside the box
        c[i] = min(max(c[i], lo + 1.2 * r), hi - 1.2 * r)
    n = [0.0, 0.0, 1.0] if dims == 2 else [rng.uniform(-1, 1) for _ in range(3)]
    if dims == 2:
        c[2] = 0.0
    if all(abs(x) < 0.05 for x in n):
        n = [0.0, 0.0, 1.0]
    if kind == "circle":
        return "circle:%s:%s:%.6g%s" % (fmt(c), fmt(n), r, rng.choice(["", "", ":open"]))
    a0 = rng.uniform(0, 300)
    return "arc:%s:%s:%.6g:%.4g,%.4g" % (fmt(c), fmt(n), r, a0, a0 + rng.uniform(20, 300))

def jobs(fields_file, count, seed, cap):
    rng = random.Random(seed)
    fields = parse_fields(open(fields_file).read())
    boxes = {f["name"]: domain_box(f) for f in fields}
    steady = [f for f in fields if f["steady"]]
    unsteady = [f for f in fields if not f["steady"]]
    if not steady or not unsteady:
        raise SystemExit("soak: `orthofront fields` listed no steady or no unsteady fields")
    budget = max(1, cap // 4)
    for i in range(count):
        path = rng.random() < 0.5
        f = rng.choice(unsteady if path else steady)
        box = boxes[f["name"]]
        dims = len(box)
        extent = min(hi - lo for lo, hi in box)
        args = ["path" if path else "stream", "--field", f["name"],
                "--seed", make_seed(rng, box, 2 if (path and dims == 2) else 3),
                "--seed-count", str(rng.randint(3, 40)),
                "--edge", "%.4g" % (extent * rng.uniform(0.01, 0.06)),
                "--steps", str(rng.randint(5, 400) if not path else rng.randint(20, 3000)),
                "--memory", rng.choice(["64MiB", "128MiB", "256MiB", "512MiB", "1GiB"]),
                "--time-budget", str(budget)]
        if path:
            t0 = rng.uniform(0, 5)
            args += ["--t0", "%.4g" % t0, "--t1", "%.4g" % (t0 + rng.uniform(0.5, 20))]
            if dims == 2 and rng.random() < 0.3:
                args.append("--spacetime-out")
        elif rng.random() < 0.15:
            args += ["--method", "timeline"]
        if rng.random() < 0.3:
            args += ["--row-skip", rng.choice(["off", "vertex", "run"])]
        if rng.random() < 0.2:
            args += ["--insertion", rng.choice(["streamline", "cubic", "linear"])]
        if rng.random() < 0.1:
            args += ["--negative-alpha", "keep"]
        if rng.random() < 0.1:
            args += ["--integrator", "rk4"]
        ext = rng.choice([".vtp", ".ply", ".obj"])
        args += ["--out", "@DIR@/mesh" + ext, "--report", "@DIR@/report.json", "--quiet"]
        if not path and rng.random() < 0.1:
            args += ["--exr", "@DIR@/fronts.exr"]
        print(" ".join(args))

# --- reading meshes back -------------------------------------------------------------------

VTK_TYPES = {"Int8": "b", "UInt8": "B", "Int16": "h", "UInt16": "H", "Int32": "i",
             "UInt32": "I", "Int64": "q", "UInt64": "Q", "Float32": "f", "Float64": "d"}
PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
             "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I",
             "uint32": "I", "float": "f", "float32": "f", "double": "d", "float64": "d"}

def vtp_array(node, header="Q"):
    fmt_ = node.get("format")
    code = VTK_TYPES[node.get("type")]
    if fmt_ == "ascii":
        return [float(x) if code in "fd" else int(x) for x in node.text.split()]
    if fmt_ != "binary":
        raise ValueError("DataArray %s: format %s" % (node.get("Name"), fmt_))
    raw = base64.b64decode("".join(node.text.split()))
    hs = struct.calcsize("<" + header)
    (nbytes,) = struct.unpack_from("<" + header, raw, 0)
    size = struct.calcsize(code)
    if nbytes % size or hs + nbytes > len(raw):
        raise ValueError("DataArray %s: %d bytes declared, %d present"
                         % (node.get("Name"), nbytes, len(raw) - hs))
    return list(struct.unpack_from("<%d%s" % (nbytes // size, code), raw, hs))

def read_vtp(path):
    root = ET.parse(path).getroot()
    if root.get("compressor"):
        raise ValueError("compressed .vtp is not read by this checker")
    header = "Q" if root.get("header_type", "UInt32") == "UInt64" else "I"
    pieces = root.findall("./PolyData/Piece")
    if len(pieces) != 1:
        raise ValueError("%d pieces" % len(pieces))
    piece = pieces[0]
    n = int(piece.get("NumberOfPoints"))
    xyz = vtp_array(piece.find("./Points/DataArray"), header)
    if len(xyz) != 3 * n:
        raise ValueError("%d point coordinates for %d points" % (len(xyz), n))
    points = [tuple(xyz[3 * i:3 * i + 3]) for i in range(n)]
    arrays = {a.get("Name"): a for a in piece.findall("./Polys/DataArray")}
    conn, offsets = vtp_array(arrays["connectivity"], header), vtp_array(arrays["offsets"], header)
    if len(offsets) != int(piece.get("NumberOfPolys")):
        raise ValueError("%d offsets for %s polys" % (len(offsets), piece.get("NumberOfPolys")))
    faces, start = [], 0
    for end in offsets:
        if end < start or end > len(conn):
            raise ValueError("offsets not increasing or past the connectivity")
        faces.append(conn[start:end])
        start = end
    for a in piece.findall("./PointData/DataArray"):
        if len(vtp_array(a, header)) != n * int(a.get("NumberOfComponents", "1")):
            raise ValueError("point array %s does not have %d tuples" % (a.get("Name"), n))
    return points, faces

def read_ply(path):
    data = open(path, "rb").read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise ValueError("no PLY header")
    elements, encoding = [], None
    for line in data[:end].decode("ascii").splitlines()[1:]:
        w = line.split()
        if not w or w[0] == "comment":
            continue
        if w[0] == "format":
            encoding = w[1]
        elif w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property":
            elements[-1][2].append(w[1:])
    if encoding != "binary_little_endian":
        raise ValueError("PLY encoding %s (expected binary_little_endian)" % encoding)
    pos, points, faces = end + len(b"end_header\n"), [], []
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            code = "<" + "".join(PLY_TYPES[p[0]] for p in props)
            size = struct.calcsize(code)
            names = [p[-1] for p in props]
            ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
            for _ in range(count):
                row = struct.unpack_from(code, data, pos)
                pos += size
                if name == "vertex":
                    points.append((row[ix], row[iy], row[iz]))
        else:
            if len(props) != 1:
                raise ValueError("element %s: a list and other properties" % name)
            _, ctype, itype, _ = props[0]
            cc, ic = "<" + PLY_TYPES[ctype], PLY_TYPES[itype]
            for _ in range(count):
                (k,) = struct.unpack_from(cc, data, pos)
                pos += struct.calcsize(cc)
                faces.append(list(struct.unpack_from("<%d%s" % (k, ic), data, pos)))
                pos += k * struct.calcsize(ic)
    if pos != len(data):
        raise ValueError("%d bytes after the last element" % (len(data) - pos))
    return points, faces

def read_obj(path):
    points, faces = [], []
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            points.append(tuple(float(x) for x in w[1:4]))
        elif w[0] == "f":
            faces.append([int(x.split("/")[0]) - 1 for x in w[1:]])
    return points, faces

def check(mesh, report, strict):
    """Problems with a written mesh (and its report), one string each."""
    problems = []
    try:
        reader = {"vtp": read_vtp, "ply": read_ply, "obj": read_obj}[mesh.rsplit(".", 1)[-1]]
        points, faces = reader(mesh)
    except Exception as e:
        return ["%s does not read back: %s: %s" % (mesh, type(e).__name__, e)], ""
    n = len(points)
    bad = sum(1 for p in points if not all(math.isfinite(x) for x in p))
    if bad:
        problems.append("%d vertices with non-finite positions" % bad)
    edges, bad_faces = {}, 0
    for f in faces:
        if len(f) not in (3, 4) or len(set(f)) != len(f) or any(not 0 <= i < n for i in f):
            bad_faces += 1
            continue
        for a, b in zip(f, f[1:] + f[:1]):
            key = (a, b) if a < b else (b, a)
            edges[key] = edges.get(key, 0) + 1
    if bad_faces:
        problems.append("%d faces with an index out of range, repeated, or not 3-4 sides" % bad_faces)
    shared = sum(1 for c in edges.values() if c > 2)
    if shared:
        problems.append("%d edges shared by more than two faces" % shared)
    try:
        r = json.load(open(report))
    except Exception as e:
        return problems + ["report %s does not read: %s" % (report, e)], ""
    counts, q = r.get("counts", {}), r.get("quality", {})
    if counts.get("vertices") != n or counts.get("faces") != len(faces):
        problems.append("the mesh has %d vertices and %d faces, the report says %s and %s"
                        % (n, len(faces), counts.get("vertices"), counts.get("faces")))
    if q.get("non_manifold_edges", 0):
        problems.append("report: %s non_manifold_edges" % q["non_manifold_edges"])
    # The timeline baseline is known to leave slivers (DESIGN: that is what the flow-orthogonal
    # engine improves on); its degenerate faces fail only with SOAK_STRICT=1.
    baseline = r.get("parameters", {}).get("method") == "timeline"
    if q.get("degenerate_faces", 0) and (strict or not baseline):
        problems.append("report: %s degenerate_faces" % q["degenerate_faces"])
    summary = "%d vertices, %d faces, %d folds, %d degenerate faces, stop %s%s" % (
        n, len(faces), q.get("folds", 0), q.get("degenerate_faces", 0), r.get("stop_reason"),
        "" if r.get("complete", True) else " (incomplete)")
    return problems, summary

if __name__ == "__main__":
    if sys.argv[1] == "jobs":
        jobs(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]))
    elif sys.argv[1] == "check":
        problems, summary = check(sys.argv[2], sys.argv[3], sys.argv[4] == "1")
        for p in problems:
            print(p)
        if not problems:
            print(summary)
        sys.exit(1 if problems else 0)
PY

"$binary" fields > "$work/fields.txt" 2> "$work/fields.err" || {
  echo "soak: '$binary fields' failed:" >&2; cat "$work/fields.err" >&2; exit 1; }
"$python" "$helper" jobs "$work/fields.txt" "$jobs" "$seed" "$cap" > "$work/jobs.txt" || exit 1

echo "soak: $jobs jobs against $binary (seed $seed, at most ${cap}s a job), in $work"
# Sanitizers: report, don't stop at the first finding in a library we can't fix; exit non-zero.
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
sanitizer='AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|ThreadSanitizer|MemorySanitizer|runtime error:'
start=$(date +%s)
failures=0 ok=0 partial=0 refused=0 empty=0 i=0
failed_lines=()
while IFS= read -r line; do
  i=$((i + 1))
  dir="$work/job-$i"
  mkdir -p "$dir"
  command_line=${line//@DIR@/$dir}
  read -r -a args <<< "$command_line"
  job_start=$(date +%s.%N)
  timeout -k 5 "$cap" "$binary" "${args[@]}" > "$dir/stdout" 2> "$dir/stderr"
  rc=$?
  seconds=$(awk -v a="$job_start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  mesh=$(find "$dir" -maxdepth 1 -name 'mesh.*' ! -name '*.tmp-*' | head -1)
  leftover=$(find "$dir" -maxdepth 1 -name '*.tmp-*' | head -1)
  problem=""
  if grep -Eq "$sanitizer" "$dir/stderr"; then
    problem="sanitizer report: $(grep -Em1 "$sanitizer" "$dir/stderr")"
  elif [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
    problem="still running after ${cap}s (hung?)"
  elif [ "$rc" != 0 ] && [ "$rc" != 2 ]; then
    problem="exit status $rc: $(tail -n 2 "$dir/stderr" | tr '\n' ' ')"
  elif [ "$rc" = 2 ] && ! grep -q "^orthofront: error: " "$dir/stderr"; then
    problem="exit status 2 without an 'orthofront: error:' message"
  elif [ -n "$leftover" ]; then
    problem="temporary file left behind: $leftover"
  elif [ "$rc" = 0 ] && { [ -z "$mesh" ] || [ ! -f "$dir/report.json" ]; }; then
    problem="exit status 0 but no mesh or no report written"
  elif [ "$rc" = 0 ] && [[ $command_line == *--exr* ]] && [ ! -s "$dir/fronts.exr" ]; then
    problem="exit status 0 but no --exr image written"
  fi
  verdict=""
  if [ -z "$problem" ] && [ -n "$mesh" ]; then
    if ! verdict=$("$python" "$helper" check "$mesh" "$dir/report.json" "$strict" 2>&1); then
      problem="invalid mesh: $(echo "$verdict" | tr '\n' ';')"
    fi
  fi
  if [ -n "$problem" ]; then
    failures=$((failures + 1))
    failed_lines+=("job $i: $problem"$'\n'"    $binary $command_line")
    echo "job $i FAILED (${seconds}s): $problem"
    echo "    $binary $command_line"
    continue
  fi
  if [ "$rc" = 2 ] && [ -z "$mesh" ]; then
    refused=$((refused + 1))
    echo "job $i refused (${seconds}s): $(grep -m1 '^orthofront: error: ' "$dir/stderr" | cut -c1-160)"
  else
    [ "$rc" = 2 ] && partial=$((partial + 1)) || ok=$((ok + 1))
    case $verdict in *" 0 faces,"*) empty=$((empty + 1)) ;; esac
    echo "job $i ok (${seconds}s, exit $rc): ${args[0]} ${args[2]}: $verdict"
  fi
  [ "$keep" = 1 ] || rm -rf "$dir"
done < "$work/jobs.txt"

elapsed=$(( $(date +%s) - start ))
echo
echo "soak summary: $i jobs in ${elapsed}s (seed $seed, binary $binary): $((ok + partial + refused)) passed" \
     "($ok complete or warned, $partial partial with exit 2, $refused refused; $empty with no faces)," \
     "$failures failed"
for f in "${failed_lines[@]+"${failed_lines[@]}"}"; do echo "  $f"; done
if [ "$failures" != 0 ]; then
  trap - EXIT  # the failed jobs' folders (stderr, mesh, report) are what to look at
  echo "the failed jobs' files (stdout, stderr, mesh, report) are in $work"
  exit 1
fi
