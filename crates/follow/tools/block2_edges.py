#!/usr/bin/env python3
"""block2 shared-edge coverage of a follow run, recomputed from its surface_model.json
without the sim crate (issue 45 acceptance 4: an independent check of run.json).

Usage: block2_edges.py RUN_DIR [FACES_LEFT_OUT]   e.g. block2_edges.py D +x,+xch for arm4
(faces: +x, +xch, top, -xch, -x, +y, -y; the bottom is never counted).
"""
# Two rules: (a) run.json's, a shared edge between ANY polygon on face A and any on
# face B within λ of the true edge sample (a polygon is "on" a face when its normal is
# within μ and its centroid within λ of the plane; run.json also asks its centroid or a
# vertex within λ of the face's triangles, left out here); (b) the surface crate's sweeps
# test's, only the polygon with the most points on each face counts.
import json, sys, math
L=0.05; cosmu=math.cos(math.radians(10))
def n(v):
    s=math.sqrt(sum(x*x for x in v)); return [x/s for x in v]
# block2 faces off the table: (normal, offset, name)
prof=[(-0.5,0.0),(0.5,0.0),(0.5,0.3),(0.2,0.6),(-0.15,0.6),(-0.5,0.4)]
faces=[]
names=['bottom','+x','+xch','top','-xch','-x']
for i in range(6):
    (x0,z0),(x1,z1)=prof[i],prof[(i+1)%6]
    dx,dz=x1-x0,z1-z0
    nn=n([dz,0,-dx])
    faces.append((nn, nn[0]*x0+nn[2]*z0, names[i], ((x0,z0),(x1,z1))))
faces.append(([0,1,0],0.4,'+y',None)); faces.append(([0,-1,0],0.4,'-y',None))
counted=[f for f in faces if f[2]!='bottom']
skip=set(sys.argv[2].split(',')) if len(sys.argv)>2 else set()
counted=[f for f in counted if f[2] not in skip]
# true edges: profile edges between consecutive profile faces, and profile face x ends
edges=[]
for i in range(1,6):
    for j in range(i+1,6):
        if j==i+1:
            (x,z)=prof[j]
            edges.append((names[i],names[j],[x,-0.4,z],[x,0.4,z]))
for i in range(1,6):
    (x0,z0),(x1,z1)=faces[i][3]
    for y,nm in [(0.4,'+y'),(-0.4,'-y')]:
        edges.append((names[i],nm,[x0,y,z0],[x1,y,z1]))
cn={f[2] for f in counted}
edges=[e for e in edges if e[0] in cn and e[1] in cn]
m=json.load(open(sys.argv[1]+'/surface_model.json'))
polys={s['id']:s for s in m['segments'] if s['kind']=='polygon' and not s['initial']}
def on(p,f):
    return sum(a*b for a,b in zip(p['normal'],f[0]))>cosmu and abs(sum(a*b for a,b in zip(p['centroid'],f[0]))-f[1])<L
byface={f[2]:[i for i,p in polys.items() if on(p,f)] for f in counted}
owner={k:(max(v,key=lambda i:polys[i]['points']) if v else None) for k,v in byface.items()}
def shared(A,B):
    out=[]
    for i in A:
        p=polys[i]; V=p['vertices']
        for k,e in enumerate(p['edges']):
            if e['shared_with'] in B:
                out.append((V[k],V[(k+1)%len(V)]))
    return out
def dseg(x,a,b):
    ab=[b[i]-a[i] for i in range(3)]; ax=[x[i]-a[i] for i in range(3)]
    t=max(0,min(1,sum(p*q for p,q in zip(ab,ax))/max(1e-18,sum(p*p for p in ab))))
    return math.dist(x,[a[i]+t*ab[i] for i in range(3)])
tot=[0,0,0]
for fa,fb,a,b in edges:
    Ln=math.dist(a,b); k=max(1,math.ceil(Ln/0.005))
    sa=shared(byface[fa],set(byface[fb]))+shared(byface[fb],set(byface[fa]))
    oa,ob=owner[fa],owner[fb]
    so=shared([oa],{ob})+shared([ob],{oa}) if oa and ob else []
    ca=co=0
    for i in range(k):
        x=[a[j]+(b[j]-a[j])*(i+0.5)/k for j in range(3)]
        if any(dseg(x,*s)<L for s in sa): ca+=1
        if any(dseg(x,*s)<L for s in so): co+=1
    tot[0]+=Ln; tot[1]+=Ln*ca/k; tot[2]+=Ln*co/k
    print('%5s-%-5s %.2f m: any %.1f %%, owners %.1f %%  (polys %s / %s)'%(fa,fb,Ln,100*ca/k,100*co/k,byface[fa],byface[fb]))
print('total %.2f m: any polygon %.1f %%, owners only %.1f %%'%(tot[0],100*tot[1]/tot[0],100*tot[2]/tot[0]))
