import sys; sys.path.insert(0,'/tmp/st'); import pfm
def mse(m):
    acc=None
    for s in range(8):
        w,h,img=pfm.read('/tmp/st/maps/%s-%d.pfm'%(m,s))
        if acc is None: acc=[[0.0]*w for _ in range(h)]
        for y in range(h):
            for x in range(w):
                acc[y][x]+=sum(v*v for v in img[y][x])/3/8
    return w,h,acc
w,h,a=mse('refine'); _,_,b=mse('vgc')
tot_a=sum(map(sum,a)); tot_b=sum(map(sum,b))
print('total mse refine %.4g vgc %.4g ratio %.3f'%(tot_a/(w*h),tot_b/(w*h),(tot_a/tot_b)**.5))
# positive where refine worse: red; negative: green
out=[[(max(a[y][x]-b[y][x],0)*2000,max(b[y][x]-a[y][x],0)*2000,0) for x in range(w)] for y in range(h)]
pfm.write('/tmp/st/maps/delta.pfm',w,h,out)
pfm.write('/tmp/st/maps/refine.pfm',w,h,[[(a[y][x]*2000,)*3 for x in range(w)] for y in range(h)])
pfm.write('/tmp/st/maps/vgc.pfm',w,h,[[(b[y][x]*2000,)*3 for x in range(w)] for y in range(h)])
# sum of excess by row band
for y0 in range(0,h,10):
    ex=sum(a[y][x]-b[y][x] for y in range(y0,y0+10) for x in range(w))
    print(y0, '%.4f'%ex, '%.4f'%sum(a[y][x] for y in range(y0,y0+10) for x in range(w)), '%.4f'%sum(b[y][x] for y in range(y0,y0+10) for x in range(w)))
