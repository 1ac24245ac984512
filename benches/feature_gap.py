#!/usr/bin/env python3
"""Are the input vertices a hex mesh misses on the input's sharp edges? For each
distance threshold (1 %, 0.75 %, 0.5 % of the bounding-box diagonal): how many
input vertices are farther than it from the hex boundary (exact distances to the
boundary quads as four triangles each, as benches/surface_gap.py; 5 x 5 samples
per quad until 2026-12-05), how many of them lie on a sharp edge
(dihedral angle above ANGLE degrees, default 30; the hex stage's
HexOptions::feature_angle is 40) or at a corner (three or more
sharp edges), and the largest distance over the vertices on no sharp edge
(BENCHMARKS.md "At HexGen's element counts").

    python3 benches/feature_gap.py INPUT.off|INPUT.obj HEX.vtk [ANGLE]

Needs numpy.
"""
import importlib.util
import os
import sys
from collections import Counter, defaultdict

import numpy as np

_spec = importlib.util.spec_from_file_location("surface_gap", os.path.join(os.path.dirname(os.path.abspath(__file__)), "surface_gap.py"))
sg = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sg)


def main():
    surf, hexf = sys.argv[1], sys.argv[2]
    ang=float(sys.argv[3]) if len(sys.argv)>3 else 30
    # input with faces
    if surf.endswith('.obj'):
        L=open(surf).read().split('\n')
        V=np.array([l.split()[1:4] for l in L if l.startswith('v ')],float)
        F=np.array([[int(x.split('/')[0])-1 for x in l.split()[1:4]] for l in L if l.startswith('f ')])
    else:
        t=open(surf).read().split(); nv,nf=int(t[1]),int(t[2]); V=np.array(t[4:4+3*nv],float).reshape(nv,3); F=np.array(t[4+3*nv:4+3*nv+4*nf],int).reshape(nf,4)[:,1:]
    N=np.cross(V[F[:,1]]-V[F[:,0]],V[F[:,2]]-V[F[:,0]]); N/=np.linalg.norm(N,axis=1)[:,None]
    E=defaultdict(list)
    for i,f in enumerate(F):
        for a,b in ((f[0],f[1]),(f[1],f[2]),(f[2],f[0])): E[(min(a,b),max(a,b))].append(i)
    sharp=set(); deg=Counter()
    for e,ts in E.items():
        if len(ts)==2 and np.degrees(np.arccos(np.clip(N[ts[0]]@N[ts[1]],-1,1)))>ang:
            for v in e: sharp.add(v); deg[v]+=1
    pts,cells=sg.read_vtk(hexf)
    count=Counter(); faces={}
    for c in cells:
        for f in sg.FACES:
            k=tuple(sorted(c[j] for j in f)); count[k]+=1; faces.setdefault(k,[c[j] for j in f])
    T=[]
    for k,n in count.items():
        if n!=1: continue
        q=pts[faces[k]]; c=q.mean(0)
        for j in range(4): T.append((q[j],q[(j+1)%4],c))
    T=np.array(T); diag=np.linalg.norm(V.max(0)-V.min(0))
    # exact distances to the boundary quads as four triangles each (surface_gap.point_triangles)
    d=np.array([sg.point_triangles(v,T) for v in V])/diag
    order=np.argsort(-d)
    for thr in [0.01,0.0075,0.005]:
        far=[i for i in order if d[i]>thr]
        ons=sum(1 for i in far if i in sharp); corner=sum(1 for i in far if deg[i]>=3)
        print(f"> {100*thr:.2f} %: {len(far)} vertices, on sharp edges {ons}, at corners (3+ sharp edges) {corner}; max over smooth vertices {100*max([d[i] for i in range(len(V)) if i not in sharp] or [0]):.2f} %")


if __name__ == "__main__":
    main()
