import numpy as np
_T = {'char':'i1','int8':'i1','uchar':'u1','uint8':'u1','short':'i2','int16':'i2','ushort':'u2','uint16':'u2',
      'int':'i4','int32':'i4','uint':'u4','uint32':'u4','float':'f4','float32':'f4','double':'f8','float64':'f8'}
def read_ply(path):
    with open(path,'rb') as f:
        data = f.read()
    end = data.index(b'end_header')
    end = data.index(b'\n', end) + 1
    hdr = data[:end].decode('ascii', 'replace').splitlines()
    fmt = None; elems = []
    for l in hdr:
        p = l.split()
        if not p: continue
        if p[0] == 'format': fmt = p[1]
        elif p[0] == 'element': elems.append([p[1], int(p[2]), []])
        elif p[0] == 'property':
            if p[1] == 'list': elems[-1][2].append((p[4], 'list', p[2], p[3]))
            else: elems[-1][2].append((p[2], p[1]))
    out = {}
    if fmt == 'ascii':
        lines = data[end:].decode('ascii').split('\n'); li = 0
        for name, n, props in elems:
            if name == 'face':
                rows = [lines[li+i].split() for i in range(n)]; li += n
                out['face'] = np.array([[int(v) for v in r[1:4]] for r in rows if int(r[0]) == 3], dtype=np.int64).reshape(-1,3)
            else:
                arr = np.loadtxt(lines[li:li+n], ndmin=2); li += n
                out[name] = {pr[0]: arr[:, i] for i, pr in enumerate(props)}
        return out
    bo = '<' if 'little' in fmt else '>'
    off = end
    for name, n, props in elems:
        if any(pr[1] == 'list' for pr in props) and n == 0:
            out[name] = np.zeros((0, 3), dtype=np.int64)
        elif any(pr[1] == 'list' for pr in props):
            pr = props[0]
            ct, it = _T[pr[2]], _T[pr[3]]
            cnt = np.frombuffer(data, dtype=bo+ct, count=1, offset=off)[0]
            dt = np.dtype([('n', bo+ct), ('v', bo+it, (3,))])
            arr = np.frombuffer(data, dtype=dt, count=n, offset=off)
            if len(props) == 1 and np.all(arr['n'] == 3):
                out[name] = arr['v'].astype(np.int64); off += n * dt.itemsize
            else:  # general fallback
                faces = []; o = off
                for i in range(n):
                    k = int(np.frombuffer(data, dtype=bo+ct, count=1, offset=o)[0]); o += np.dtype(ct).itemsize
                    v = np.frombuffer(data, dtype=bo+it, count=k, offset=o); o += k*np.dtype(it).itemsize
                    for j in range(1, k-1): faces.append((v[0], v[j], v[j+1]))
                out[name] = np.array(faces, dtype=np.int64).reshape(-1,3); off = o
        else:
            dt = np.dtype([(pr[0], bo+_T[pr[1]]) for pr in props])
            arr = np.frombuffer(data, dtype=dt, count=n, offset=off); off += n * dt.itemsize
            out[name] = {pr[0]: arr[pr[0]] for pr in props}
    return out
