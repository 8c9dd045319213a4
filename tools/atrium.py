#!/usr/bin/env python3
"""A Sponza-sized stand-in for measuring every method at its defaults on a large scene.

    python3 tools/atrium.py DIR    # writes DIR/atrium.obj (+ .mtl, stone.png), sun.toml, lamps.toml

An atrium 32 x 16 m with an open roof: two storeys of 48-sided columns (open cylinders), two
galleries, wavy fabric sheets (open, one-sided), two closed spheres on plinths, stone walls with
a checker texture; 268,956 triangles. sun.toml lights it with a sun and a constant sky,
lamps.toml with 16 point lights and a spot light. Each scene declares every method that runs on
it (the others are refused in one line: tools/atrium_defaults.sh), so
    penumbra capture DIR/sun.toml --method M
    penumbra chart DIR/sun.toml                (tools/atrium_chart.sh)
"""
import math, os, struct, sys, zlib
out=sys.argv[1] if len(sys.argv)>1 else '.'
os.makedirs(out,exist_ok=True)
V=[]; F={}  # material -> list of (a,b,c) 1-based
def v(p): V.append(p); return len(V)
def tri(m,a,b,c): F.setdefault(m,[]).append((a,b,c))
def quad(m,a,b,c,d): tri(m,a,b,c); tri(m,a,c,d)
def box(m,lo,hi):
    x0,y0,z0=lo; x1,y1,z1=hi
    P=[v((x,y,z)) for x in (x0,x1) for y in (y0,y1) for z in (z0,z1)]
    i=lambda a,b,c:P[a*4+b*2+c]
    quad(m,i(0,0,0),i(0,0,1),i(0,1,1),i(0,1,0)) # -x
    quad(m,i(1,0,0),i(1,1,0),i(1,1,1),i(1,0,1)) # +x
    quad(m,i(0,0,0),i(1,0,0),i(1,0,1),i(0,0,1)) # -y
    quad(m,i(0,1,0),i(0,1,1),i(1,1,1),i(1,1,0)) # +y
    quad(m,i(0,0,0),i(0,1,0),i(1,1,0),i(1,0,0)) # -z
    quad(m,i(0,0,1),i(1,0,1),i(1,1,1),i(0,1,1)) # +z
def column(m,x,z,r,y0,y1,seg,rings):
    rows=[]
    for j in range(rings+1):
        y=y0+(y1-y0)*j/rings; rr=r*(1+0.08*math.sin(math.pi*j/rings))
        rows.append([v((x+rr*math.cos(2*math.pi*k/seg),y,z+rr*math.sin(2*math.pi*k/seg))) for k in range(seg)])
    for j in range(rings):
        for k in range(seg):
            a=rows[j][k]; b=rows[j][(k+1)%seg]; c=rows[j+1][(k+1)%seg]; d=rows[j+1][k]
            quad(m,a,d,c,b)
def sheet(m,x0,x1,z,y0,y1,nx,ny):
    rows=[[v((x0+(x1-x0)*i/nx, y0+(y1-y0)*j/ny, z+0.15*math.sin(6*math.pi*i/nx)*(j/ny))) for i in range(nx+1)] for j in range(ny+1)]
    for j in range(ny):
        for i in range(nx):
            quad(m,rows[j][i],rows[j][i+1],rows[j+1][i+1],rows[j+1][i])
# shell: floor, four walls, gallery slabs at 5 m for |z| > 4
box("stone",(-16,-0.5,-8),(16,0,8))
box("stone",(-16.5,0,-8.5),(-16,12,8.5)); box("stone",(16,0,-8.5),(16.5,12,8.5))
box("stone",(-16,0,-8.5),(16,12,-8)); box("stone",(-16,0,8),(16,12,8.5))
for s in (-1,1):
    box("stone",(-16,5,min(s*4.4,s*8)),(16,5.3,max(s*4.4,s*8)))
    box("stone",(-16,9.3,min(s*4.4,s*8)),(16,9.6,max(s*4.4,s*8)))
    for i in range(12):
        x=-13.75+i*2.5
        column("column",x,s*4.7,0.4,0,5,48,30)
        column("column",x,s*4.7,0.3,5.3,9.3,48,20)
    box("stone",(-16,4.6,s*4.7-0.45),(16,5,s*4.7+0.45))
    sheet("fabric",-10,-4,s*4.2,5.3,8.5,60,30); sheet("fabric",4,10,s*4.2,5.3,8.5,60,30)
# two statues: closed spheres on plinths, 69,600 triangles each, curved like the columns
def sphere(m,cx,cy,cz,r,lat,lon):
    top=v((cx,cy+r,cz)); bottom=v((cx,cy-r,cz))
    rings=[]
    for i in range(1,lat):
        th=math.pi*i/lat
        rings.append([v((cx+r*math.sin(th)*math.cos(2*math.pi*k/lon),cy+r*math.cos(th),cz+r*math.sin(th)*math.sin(2*math.pi*k/lon))) for k in range(lon)])
    for k in range(lon):
        tri(m,top,rings[0][(k+1)%lon],rings[0][k])
        tri(m,bottom,rings[-1][k],rings[-1][(k+1)%lon])
    for i in range(len(rings)-1):
        for k in range(lon):
            a=rings[i][k]; b=rings[i][(k+1)%lon]; c=rings[i+1][(k+1)%lon]; d=rings[i+1][k]
            quad(m,a,b,c,d)
for ox in (-6,6):
    box("stone",(ox-0.8,0,-0.8),(ox+0.8,0.6,0.8))
    sphere("statue",ox,1.6,0,1.0,146,240)
# a checker texture for the floor material
def png(path,w,h,px):
    raw=b''.join(b'\0'+bytes(px(x,y) for x in range(w) for _ in range(3)) for y in range(h))
    def ch(t,d): return struct.pack('>I',len(d))+t+d+struct.pack('>I',zlib.crc32(t+d)&0xffffffff)
    open(path,'wb').write(b'\x89PNG\r\n\x1a\n'+ch(b'IHDR',struct.pack('>IIBBBBB',w,h,8,2,0,0,0))+ch(b'IDAT',zlib.compress(raw))+ch(b'IEND',b''))
png(os.path.join(out,'stone.png'),256,256,lambda x,y: 150 if ((x//32)+(y//32))%2 else 110)
with open(os.path.join(out,'atrium.mtl'),'w') as f:
    f.write("newmtl stone\nKd 0.6 0.58 0.55\nmap_Kd stone.png\n\nnewmtl column\nKd 0.7 0.68 0.62\n\nnewmtl fabric\nKd 0.6 0.1 0.1\n\nnewmtl statue\nKd 0.5 0.5 0.5\nKs 0.04 0.04 0.04\nNs 40\n")
with open(os.path.join(out,'atrium.obj'),'w') as f:
    f.write("mtllib atrium.mtl\n")
    for p in V: f.write("v %.5f %.5f %.5f\n"%p)
    # planar uvs for the floor texture: one repeat per metre from x and z
    for p in V: f.write("vt %.4f %.4f\n"%(p[0]/2,p[2]/2))
    for m,fs in F.items():
        f.write("usemtl %s\n"%m)
        for a,b,c in fs: f.write("f %d/%d %d/%d %d/%d\n"%(a,a,b,b,c,c))
print(len(V),"vertices",sum(len(x) for x in F.values()),"triangles",{m:len(x) for m,x in F.items()})
SUN = """methods = ["forward", "clustered", "shadow_volumes", "lpv", "radiosity", "sh_lightmap", "prt"]
[camera]
position = [-13.0, 1.7, 0.0]
target = [0.0, 4.0, 0.0]
fov_y_deg = 60
[environment]
type = "constant"
radiance = [0.35, 0.45, 0.6]
[[lights]]
type = "directional"
name = "sun"
direction = [0.3, -0.85, 0.2]
irradiance = [2.4, 2.2, 1.9]
[[objects]]
name = "atrium"
mesh = "asset"
path = "atrium.obj"
"""
LAMPS = """methods = ["forward", "clustered", "shadow_volumes", "vls", "lpv", "radiosity"]
[camera]
position = [-13.0, 1.7, 0.0]
target = [0.0, 2.0, 0.0]
fov_y_deg = 60
[[light_arrays]]
name = "lamps"
type = "point"
grid = [8, 1, 2]
min = [-14.0, 3.5, -6.2]
max = [14.0, 3.5, 6.2]
intensity = [3.0, 2.6, 2.0]
[[lights]]
type = "spot"
name = "key"
position = [0.0, 11.0, 0.0]
target = [6.0, 0.0, 0.0]
intensity = [60.0, 55.0, 50.0]
outer_deg = 35
[[objects]]
name = "atrium"
mesh = "asset"
path = "atrium.obj"
"""

for name,text in (("sun.toml",SUN),("lamps.toml",LAMPS)):
    with open(os.path.join(out,name),'w') as f: f.write(text)
