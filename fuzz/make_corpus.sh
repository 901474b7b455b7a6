#!/usr/bin/env bash
# Writes the seed corpus of every fuzz target into DIR (default fuzz/corpus): small valid files
# of each format, the grids and HDF5/OpenVDB files written by the project's own writers (the
# `orthofront` binary given as $ORTHOFRONT), and examples of each text syntax.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/corpus}"
bin="${ORTHOFRONT:-$here/../build/apps/orthofront}"
[ -x "$bin" ] || { echo "make_corpus.sh: no orthofront binary at $bin (set ORTHOFRONT)" >&2; exit 2; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"/{grid_vec,grid_am,grid_nrrd,grid_nhdr,grid_vti,grid_vtk,grid_vdb,vdb_file,hdf5,netcdf,pvd,mesh_vtp,mesh_ply,mesh_obj,parse_seed,parse_field,parse_bytes,job_file,checkpoint}

python3 - "$work" <<'PY'
import struct, sys, zlib, base64, os
w = sys.argv[1]
nx, ny, nz = 4, 3, 2
vals = [float((i * 7 + c) % 5) - 2.0 for i in range(nx * ny * nz) for c in range(3)]
le = struct.pack('<%df' % len(vals), *vals)
be = struct.pack('>%df' % len(vals), *vals)
open(f'{w}/a.vec', 'wb').write(struct.pack('<3i', nx, ny, nz) + le)
open(f'{w}/a.am', 'wb').write(
    b'# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\n\ndefine Lattice %d %d %d\n\n'
    b'Parameters {\n    BoundingBox 0 3 0 2 0 1,\n    CoordType "uniform"\n}\n\n'
    b'Lattice { float[3] Data } @1\n\n# Data section follows\n@1\n' % (nx, ny, nz) + le + b'\n')
hdr = (b'NRRD0004\ntype: float\ndimension: 4\nsizes: 3 %d %d %d\nkinds: vector domain domain domain\n'
       b'space directions: none (1,0,0) (0,1,0) (0,0,1)\nspace origin: (0,0,0)\n' % (nx, ny, nz))
open(f'{w}/raw.nrrd', 'wb').write(hdr + b'endian: little\nencoding: raw\n\n' + le)
open(f'{w}/gz.nrrd', 'wb').write(hdr + b'endian: big\nencoding: gzip\n\n' + zlib.compress(be))
open(f'{w}/ascii.nrrd', 'wb').write(hdr + b'encoding: ascii\n\n' + ' '.join('%g' % v for v in vals).encode() + b'\n')
ascii_vals = ' '.join('%g' % v for v in vals)
open(f'{w}/a.vtk', 'w').write(
    '# vtk DataFile Version 3.0\nfield\nASCII\nDATASET STRUCTURED_POINTS\n'
    f'DIMENSIONS {nx} {ny} {nz}\nORIGIN 0 0 0\nSPACING 1 1 1\nPOINT_DATA {nx*ny*nz}\n'
    f'VECTORS velocity float\n{ascii_vals}\n')
open(f'{w}/b.vtk', 'wb').write(
    b'# vtk DataFile Version 3.0\nfield\nBINARY\nDATASET STRUCTURED_POINTS\n'
    + f'DIMENSIONS {nx} {ny} {nz}\nORIGIN 0 0 0\nSPACING 1 1 1\nPOINT_DATA {nx*ny*nz}\n'.encode()
    + b'VECTORS velocity float\n' + be + b'\n')
def vti(encoding):
    if encoding == 'ascii':
        data, fmt = ascii_vals, 'ascii'
    else:
        raw = le
        if encoding == 'zlib':
            comp = zlib.compress(raw)
            header = struct.pack('<4I', 1, len(raw), len(raw), len(comp))
            data, fmt = base64.b64encode(header).decode() + base64.b64encode(comp).decode(), 'binary'
        else:
            data, fmt = base64.b64encode(struct.pack('<I', len(raw)) + raw).decode(), 'binary'
    comp_attr = ' compressor="vtkZLibDataCompressor"' if encoding == 'zlib' else ''
    return (f'<?xml version="1.0"?>\n<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian"'
            f' header_type="UInt32"{comp_attr}>\n<ImageData WholeExtent="0 {nx-1} 0 {ny-1} 0 {nz-1}" '
            f'Origin="0 0 0" Spacing="1 1 1">\n<Piece Extent="0 {nx-1} 0 {ny-1} 0 {nz-1}">\n'
            f'<PointData Vectors="velocity">\n<DataArray type="Float32" Name="velocity" '
            f'NumberOfComponents="3" format="{fmt}">{data}</DataArray>\n</PointData>\n</Piece>\n'
            f'</ImageData>\n</VTKFile>\n')
for e in ('ascii', 'binary', 'zlib'):
    open(f'{w}/{e}.vti', 'w').write(vti(e))

# A detached NRRD header, a NUL, then its data file's bytes (the grid_nhdr target splits them).
open(f'{w}/a.nhdr', 'wb').write(hdr.replace(b'NRRD0004', b'NRRD0004') +
                                 b'endian: little\nencoding: raw\ndata file: data.raw\n\0' + le)

# A classic NetCDF-3 file (the format is plain big-endian records): x(x), y(y), time(time) with
# units, and u, v of (time, y, x); one step.
def nc_name(n):
    b = n.encode()
    return struct.pack('>i', len(b)) + b + b'\0' * (-len(b) % 4)
def nc_text_att(name, text):
    b = text.encode()
    return nc_name(name) + struct.pack('>ii', 2, len(b)) + b + b'\0' * (-len(b) % 4)
dims = [('time', 0), ('y', ny), ('x', nx)]  # time: the record dimension
variables = [('time', [0], [('units', 'days since 2000-01-01')], 6),
             ('y', [1], [('units', 'm')], 6), ('x', [2], [('units', 'm')], 6),
             ('u', [0, 1, 2], [('units', 'm s-1')], 5), ('v', [0, 1, 2], [('units', 'm s-1')], 5)]
def header(begins):
    h = b'CDF\x01' + struct.pack('>i', 1)
    h += struct.pack('>ii', 10, len(dims)) + b''.join(nc_name(n) + struct.pack('>i', l) for n, l in dims)
    h += struct.pack('>ii', 0, 0)
    h += struct.pack('>ii', 11, len(variables))
    for (name, ids, atts, kind), begin in zip(variables, begins):
        size = (8 if kind == 6 else 4) * (1 if ids == [0] else nx * ny if ids[0] == 0 else dict(dims)[name])
        h += nc_name(name) + struct.pack('>i', len(ids)) + b''.join(struct.pack('>i', i) for i in ids)
        h += struct.pack('>ii', 12, len(atts)) + b''.join(nc_text_att(a, t) for a, t in atts)
        h += struct.pack('>iii', kind, size, begin)
    return h
fixed = {'y': struct.pack('>%dd' % ny, *range(ny)), 'x': struct.pack('>%dd' % nx, *range(nx))}
record = {'time': struct.pack('>d', 0.0), 'u': struct.pack('>%df' % (nx * ny), *([1.0] * nx * ny)),
          'v': struct.pack('>%df' % (nx * ny), *([0.5] * nx * ny))}
length = len(header([0] * len(variables)))
at = length
order = [v[0] for v in variables]
offsets = {}
for name in ('y', 'x'):
    offsets[name] = at
    at += len(fixed[name])
for name in ('time', 'u', 'v'):
    offsets[name] = at
    at += len(record[name])
data = header([offsets[n] for n in order])
assert len(data) == length
data += fixed['y'] + fixed['x'] + record['time'] + record['u'] + record['v']
open(f'{w}/a.nc', 'wb').write(data)

# A ParaView collection of the two steps the pvd target puts beside it.
open(f'{w}/a.pvd', 'w').write(
    '<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0">\n<Collection>\n'
    '<DataSet timestep="0" part="0" file="a.vti"/>\n<DataSet timestep="1.5" file="b.vti"/>\n'
    '</Collection>\n</VTKFile>\n')
PY
cp "$work/a.vec" "$out/grid_vec/"
cp "$work/a.am" "$out/grid_am/"
cp "$work"/*.nrrd "$out/grid_nrrd/"
cp "$work"/*.vtk "$out/grid_vtk/"
cp "$work"/*.vti "$out/grid_vti/"
cp "$work/a.nhdr" "$out/grid_nhdr/"
cp "$work/a.nc" "$out/netcdf/"
cp "$work/a.pvd" "$out/pvd/"

# OpenVDB and HDF5 files from the project's writers.
"$bin" convert "$work/raw.nrrd" --out "$out/grid_vdb/a.vdb" --quiet
cp "$out/grid_vdb/a.vdb" "$out/vdb_file/"
"$bin" convert "$work/raw.nrrd" "$work/gz.nrrd" --dt 1 --out "$out/vdb_file/series.vdb" --quiet
cp "$out/vdb_file/series.vdb" "$out/grid_vdb/"
"$bin" convert "$work/raw.nrrd" --out "$out/hdf5/steady.h5" --quiet
for codec in lz4 zstd gzip none; do
  "$bin" generate --field double-gyre --resolution 9,5 --steps 3 --t1 2 --brick 4 --compress "$codec" \
    --out "$out/hdf5/bricked-$codec.h5" --quiet
done
"$bin" generate --field double-gyre --resolution 9,5 --steps 3 --t1 2 --layout chunked \
  --out "$out/hdf5/chunked.h5" --quiet
"$bin" generate --field double-gyre --resolution 9,5 --steps 3 --t1 2 --layout per-step --compress gzip \
  --out "$out/hdf5/per-step.h5" --quiet
rm -f "$out"/hdf5/*.xmf

# Meshes from the project's writers.
for ext in vtp ply obj; do
  "$bin" stream --field saddle --seed line:-0.5,0.5,0:0.5,0.5,0 --seed-count 4 --steps 4 \
    --out "$work/m.$ext" >/dev/null
  cp "$work/m.$ext" "$out/mesh_$ext/"
done

# Job files, and a checkpoint state of one (its payload: the magic and CRC-32 are the target's).
cat >"$work/job.toml" <<'TOML'
[job]
field = "double-gyre"
[defaults]
edge = 0.05
seed_count = 8
[[surface]]
name = "s"
kind = "stream"
field = "saddle3d"
seed = "line:-3,1,1:-3,1,3"
steps = 400
[[rake]]
name = "r"
seed = "line:0.2,0.2,0:0.2,0.8,0"
offset = [0.3, 0.0]
count = 2
t1 = 2.0
TOML
cp "$work/job.toml" "$out/job_file/"
printf '%s\n' '{"job": {"field": "saddle3d"}, "surface": [{"name": "a", "kind": "stream", "seed": "line:-3,1,1:-3,1,3", "steps": 40}]}' >"$out/job_file/job.json"
"$bin" batch "$work/job.toml" --out "$work/batch" --checkpoint-every 0.000001 --fail-after-steps 5 \
  --quiet >/dev/null 2>&1 || true
for state in "$work"/batch/.checkpoint/*.state; do
  [ -f "$state" ] || continue
  magic=22  # "orthofront-checkpoint\n"
  size=$(stat -c %s "$state")
  tail -c +$((magic + 1)) "$state" | head -c $((size - magic - 4)) >"$out/checkpoint/$(basename "$state")"
done

# Text syntaxes.
i=0
for s in 'line:0,0,0:1,1,1' 'circle:0,0,0:0,0,1:0.5' 'circle:0,0,0:0,0,1:0.5:open' \
         'arc:0,0,0:0,0,1:1:0,90' 'line:1e300,0,0:-1e300,0,0'; do
  printf '%s' "$s" > "$out/parse_seed/$((i++))"
done
i=0
for s in saddle 'lorenz:sigma=10,rho=28,beta=2.66667' 'double-gyre:A=0.1,eps=0.25' \
         'abc' 'sinus' 'moving-spiral'; do
  printf '%s' "$s" > "$out/parse_field/$((i++))"
done
i=0
for s in 512MiB 2GiB 1.5GB 100 '64 KiB' 1e3kB; do
  printf '%s' "$s" > "$out/parse_bytes/$((i++))"
done
echo "corpus written to $out"
