#!/usr/bin/env python3
"""How many feature curves an input has at a median dihedral angle of 40 and of
60 degrees (HexOptions::feature_median_angle; curves as surface::detect_features
and prune_features build them: edges above 40 degrees chained between corners,
a corner where other than two sharp edges meet or the chain turns by more than
45 degrees, curves shorter than 3 % of the bounding-box diagonal dropped), and
for each curve kept at 40: its median dihedral angle and the median / 90th
percentile of the dihedral angles of the other edges at its vertices (flat
neighbours: a crease; rough ones: a coarse tessellation). BENCHMARKS.md
"Narrow patches merged".

    python3 benches/feature_curves.py INPUT.off|INPUT.obj|INPUT.stl

Needs numpy.
"""
import sys, numpy as np
from collections import defaultdict
def load(path):
    V=[];F=[]
    if path.endswith('.off'):
        t=open(path).read().split(); nv,nf=int(t[1]),int(t[2]); i=4
        for k in range(nv): V.append([float(x) for x in t[i:i+3]]); i+=3
        for k in range(nf): n=int(t[i]); F.append([int(x) for x in t[i+1:i+1+n]][:3]); i+=1+n
    elif path.endswith('.obj'):
        for l in open(path):
            s=l.split()
            if not s: continue
            if s[0]=='v': V.append([float(x) for x in s[1:4]])
            if s[0]=='f': F.append([int(x.split('/')[0])-1 for x in s[1:4]])
    else:
        import struct
        d=open(path,'rb').read()
        if d[:5]==b'solid' and b'facet' in d[:300]:
            pts=[]
            for l in d.decode().splitlines():
                s=l.split()
                if s and s[0]=='vertex': pts.append(tuple(float(x) for x in s[1:4]))
        else:
            n=struct.unpack('<I',d[80:84])[0]; pts=[]
            for k in range(n):
                vals=struct.unpack('<12f',d[84+50*k:84+50*k+48]); pts+= [tuple(vals[3:6]),tuple(vals[6:9]),tuple(vals[9:12])]
        idx={}
        for p in pts: idx.setdefault(p,len(idx))
        V=list(idx.keys()); F=[[idx[pts[3*k+j]] for j in range(3)] for k in range(len(pts)//3)]
    return np.array(V),np.array(F)
V,F=load(sys.argv[1])
N=np.cross(V[F[:,1]]-V[F[:,0]],V[F[:,2]]-V[F[:,0]]); N/=np.maximum(np.linalg.norm(N,axis=1),1e-300)[:,None]
et=defaultdict(list)
for t,f in enumerate(F):
    for k in range(3):
        a,b=f[k],f[(k+1)%3]; et[(min(a,b),max(a,b))].append(t)
ang={}
sharp=[]
for e,ts in et.items():
    a=180.0 if len(ts)!=2 else np.degrees(np.arccos(np.clip(N[ts[0]]@N[ts[1]],-1,1)))
    ang[e]=a
    if a>40: sharp.append(e)
adj=defaultdict(list)
for a,b in sharp: adj[a].append(b); adj[b].append(a)
corner=set()
for v,a in adj.items():
    if len(a)!=2: corner.add(v); continue
    d1=V[v]-V[a[0]]; d2=V[a[1]]-V[v]
    if d1@d2/(np.linalg.norm(d1)*np.linalg.norm(d2))<np.cos(np.radians(45)): corner.add(v)
used=set(); curves=[]
def walk(s,n):
    vs=[s,n]; used.add((min(s,n),max(s,n))); p,c=s,n
    while c not in corner and c!=s:
        nx=[w for w in adj[c] if w!=p and (min(c,w),max(c,w)) not in used]
        if not nx: break
        w=nx[0]; used.add((min(c,w),max(c,w))); vs.append(w); p,c=c,w
    return vs
for v in corner:
    for w in adj[v]:
        if (min(v,w),max(v,w)) not in used: curves.append(walk(v,w))
for e in sharp:
    if e not in used: curves.append(walk(*e))
diag=np.linalg.norm(V.max(0)-V.min(0))
res={}
for m in (40,60):
    k=0
    for c in curves:
        L=sum(np.linalg.norm(V[c[i+1]]-V[c[i]]) for i in range(len(c)-1))
        med=sorted(ang[(min(c[i],c[i+1]),max(c[i],c[i+1]))] for i in range(len(c)-1))
        med=med[len(med)//2]
        if L>=0.03*diag and med>=m: k+=1
    res[m]=k
print(sys.argv[1].split('/')[-1], 'curves median>=40:',res[40],' >=60:',res[60])
vert_edges=defaultdict(list)
for e in et: vert_edges[e[0]].append(e); vert_edges[e[1]].append(e)
sharpset=set(sharp)
out=[]
for c in curves:
    L=sum(np.linalg.norm(V[c[i+1]]-V[c[i]]) for i in range(len(c)-1))
    med=sorted(ang[(min(c[i],c[i+1]),max(c[i],c[i+1]))] for i in range(len(c)-1)); med=med[len(med)//2]
    if L<0.03*diag or med<40: continue
    nb=[ang[e] for v in c for e in vert_edges[v] if e not in sharpset]
    nbm=np.median(nb) if nb else 0
    nb90=np.percentile(nb,90) if nb else 0
    out.append((round(float(med),1),round(float(nbm),1),round(float(nb90),1)))
out.sort()
print('  (median, nb median, nb p90):', out[:40])
