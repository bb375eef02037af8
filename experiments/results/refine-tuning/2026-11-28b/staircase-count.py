import sys; sys.path.insert(0,'/tmp/st'); import pfm
for m in ['refine','vgc','vgc_dgs']:
    w,h,img=pfm.read('/tmp/st/maps/ov-%s.pfm'%m)
    def colored(p): return max(p)-min(p)>0.1
    tot=sum(colored(img[y][x]) for y in range(h) for x in range(w))
    box=sum(colored(img[y][x]) for y in range(95,140) for x in range(150,245))
    box2=sum(colored(img[y][x]) for y in range(45,100) for x in range(125,200))
    print(m,tot,box,box2)
