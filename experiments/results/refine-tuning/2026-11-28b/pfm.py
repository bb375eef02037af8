import struct, sys
def read(path):
    with open(path,'rb') as f:
        hdr=f.readline().strip(); dims=f.readline().split(); scale=float(f.readline())
        w,h=int(dims[0]),int(dims[1]); c=3 if hdr==b'PF' else 1
        data=f.read(); fmt=('<' if scale<0 else '>')+'%df'%(w*h*c)
        vals=struct.unpack(fmt,data)
    # pfm rows bottom to top
    img=[[None]*w for _ in range(h)]
    for y in range(h):
        row=vals[y*w*c:(y+1)*w*c]
        img[h-1-y]=[row[x*c:(x+1)*c] for x in range(w)]
    return w,h,img
def write(path,w,h,img):
    with open(path,'wb') as f:
        f.write(b'PF\n%d %d\n-1.0\n'%(w,h))
        for y in range(h-1,-1,-1):
            for x in range(w):
                f.write(struct.pack('<3f',*img[y][x]))
