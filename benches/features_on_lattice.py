#!/usr/bin/env python3
"""Which inputs have lattice nodes on their sharp edges: for each voxel
resolution, the voxel fallback's lattice in the working frame (the input centred
and scaled to 2 along its longest bounding-box edge; `resolution` voxels along
it, the lattice centred on the bounding box, as geometry::voxel::voxelize) and
the count of lattice points within 1e-9 of a sharp edge (dihedral angle above
40 degrees, the hex stage's feature angle). BENCHMARKS.md "Features on the
lattice".

    python3 benches/features_on_lattice.py MESH.off|obj|stl 24,30,48

Prints the mesh, its sharp-edge count and the resolutions with any such point.
Needs numpy.
"""
import struct
import sys
from collections import defaultdict

import numpy as np

def load(p):
    if p.endswith('.off'):
        t=open(p).read().split(); i=0
        if t[0]=='OFF': i=1
        nv,nf=int(t[i]),int(t[i+1]); i+=3
        V=np.array(t[i:i+3*nv],float).reshape(nv,3); i+=3*nv; F=[]
        for _ in range(nf):
            k=int(t[i]); F.append([int(x) for x in t[i+1:i+1+k]]); i+=1+k
    elif p.endswith('.obj'):
        V=[];F=[]
        for l in open(p):
            if l.startswith('v '): V.append([float(x) for x in l.split()[1:4]])
            elif l.startswith('f '): F.append([int(x.split('/')[0])-1 for x in l.split()[1:]])
        V=np.array(V)
    else:
        d=open(p,'rb').read()
        if d[:5]==b'solid' and b'facet' in d[:300]:
            pts=[];
            for l in d.decode().splitlines():
                l=l.strip()
                if l.startswith('vertex'): pts.append([float(x) for x in l.split()[1:4]])
        else:
            n=struct.unpack('<I',d[80:84])[0]; pts=[]
            for k in range(n):
                o=84+50*k; v=struct.unpack('<12f',d[o:o+48]); pts+= [v[3:6],v[6:9],v[9:12]]
        pts=np.array(pts); u,inv=np.unique(pts.round(9),axis=0,return_inverse=True); V=u; F=inv.reshape(-1,3).tolist()
    T=[]
    for f in F:
        for k in range(1,len(f)-1): T.append([f[0],f[k],f[k+1]])
    return np.array(V),np.array(T)
V,T=load(sys.argv[1])
lo,hi=V.min(0),V.max(0); L=(hi-lo).max(); c=(lo+hi)/2
W=(V-c)*(2/L)
N=np.cross(W[T[:,1]]-W[T[:,0]],W[T[:,2]]-W[T[:,0]]); N/=np.linalg.norm(N,axis=1)[:,None]+1e-300
et=defaultdict(list)
for t,f in enumerate(T):
    for k in range(3):
        a,b=f[k],f[(k+1)%3]; et[(min(a,b),max(a,b))].append(t)
sharp=[(a,b) for (a,b),ts in et.items() if len(ts)==2 and N[ts[0]]@N[ts[1]]<np.cos(np.radians(40))]
bl,bh=W.min(0),W.max(0); size=bh-bl; cw=(bl+bh)/2; lw=size.max()
hits={}
for res in [int(x) for x in sys.argv[2].split(',')]:
    h=lw/res; dims=np.maximum(np.ceil(size/h),1); lo_l=cw-dims*h/2
    n=0
    for a,b in sharp:
        A=(W[a]-lo_l)/h; B=(W[b]-lo_l)/h
        mn=np.floor(np.minimum(A,B)-1e-7); mx=np.ceil(np.maximum(A,B)+1e-7)
        if np.prod(mx-mn+1)>5000: continue
        g=np.stack(np.meshgrid(*[np.arange(mn[i],mx[i]+1) for i in range(3)],indexing='ij'),-1).reshape(-1,3)
        ab=B-A; l2=ab@ab
        t=np.clip(((g-A)@ab)/l2,0,1); d=np.linalg.norm(A+t[:,None]*ab-g,axis=1)*h
        n+=(d<1e-9).sum()
    hits[res]=int(n)
print(sys.argv[1].split('/')[-1], len(sharp), {r:n for r,n in hits.items() if n})
