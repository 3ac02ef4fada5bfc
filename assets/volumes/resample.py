# Resamples the 1 mm MNI ICBM 2009a template (NIfTI-1, uint8, 197x233x189)
# trilinearly to n^3 voxels covering the same box, updating dim, pixdim and
# the sform: python3 resample.py 128 out.nii.gz [original.nii.gz]
# (pure Python, no numpy; the same formula as VolumeData::resample).
import gzip, struct, sys
src = gzip.open(sys.argv[3] if len(sys.argv) > 3 else 'mni_icbm152_t1_09a.nii.gz').read()
hdr = bytearray(src[:352]); data = src[352:]
dim = struct.unpack_from('<8h', hdr, 40); pix = list(struct.unpack_from('<8f', hdr, 76))
w, h, d = dim[1], dim[2], dim[3]
n = int(sys.argv[1])
sc = [(w-1)/(n-1), (h-1)/(n-1), (d-1)/(n-1)]
out = bytearray(n*n*n); o = 0
for k in range(n):
    pz = k*sc[2]; z0 = min(int(pz), d-2); fz = pz - z0
    for j in range(n):
        py = j*sc[1]; y0 = min(int(py), h-2); fy = py - y0
        b00 = w*(y0 + h*z0); b10 = w*(y0+1 + h*z0); b01 = w*(y0 + h*(z0+1)); b11 = w*(y0+1 + h*(z0+1))
        for i in range(n):
            px = i*sc[0]; x0 = min(int(px), w-2); fx = px - x0
            def lx(b): return data[b+x0]*(1-fx) + data[b+x0+1]*fx
            v = (lx(b00)*(1-fy) + lx(b10)*fy)*(1-fz) + (lx(b01)*(1-fy) + lx(b11)*fy)*fz
            out[o] = max(0, min(255, int(v + 0.5))); o += 1
struct.pack_into('<8h', hdr, 40, 3, n, n, n, 1, 1, 1, 1)
for a in range(3): pix[a+1] *= sc[a]
struct.pack_into('<8f', hdr, 76, *pix)
for r, off in enumerate((280, 296, 312)):
    row = list(struct.unpack_from('<4f', hdr, off))
    for a in range(3): row[a] *= sc[a]
    struct.pack_into('<4f', hdr, off, *row)
# No name and no time in the gzip header: the same bytes on every run.
with open(sys.argv[2], 'wb') as raw:
    with gzip.GzipFile(filename='', mode='wb', fileobj=raw, compresslevel=9, mtime=0) as f:
        f.write(bytes(hdr) + bytes(out))
