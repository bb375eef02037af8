import csv, sys, math, collections
def load(p):
    d=collections.defaultdict(list)
    for r in csv.DictReader(open(p)):
        if r['status']!='ok': continue
        d[(r['scene'],r['application'],r['caches'],r['placement'])].append((int(r['seed']),float(r['rmse']),float(r['flip'])))
    return d
base=load(sys.argv[1]); var=load(sys.argv[2])
ratios=[];loss=win=0
for k in sorted(var):
    sc,app,n,pl=k
    if pl!='refine': continue
    v=sorted(var[k]); 
    def ms(x):
        m=sum(x)/len(x); sd=(sum((a-m)**2 for a in x)/(len(x)-1))**.5 if len(x)>1 else 0; return m,sd/len(x)**.5
    vm,vs=ms([a[1] for a in v])
    best=None
    for pl2 in ['im','sd','sd+as','vgc','vgc+dgs']:
        b=base.get((sc,app,n,pl2))
        if not b: continue
        bm,bs=ms([a[1] for a in b])
        if best is None or bm<best[1]: best=(pl2,bm,bs)
    dg=base.get((sc,app,n,'vgc+dgs')); dgm=ms([a[1] for a in dg])[0] if dg else float('nan')
    im=base.get((sc,app,n,'im')); imf=ms([a[2] for a in im])[0] if im else float('nan')
    vf=ms([a[2] for a in v])[0]
    r=vm/best[1]; se=(vs**2+best[2]**2)**.5
    mark='-' if vm-best[1]>2*se else ('+' if best[1]-vm>2*se else ' ')
    loss+=mark=='-'; win+=mark=='+'
    ratios.append(vm/dgm)
    print('%-34s %-14s %5s best %-7s %.5f refine %.5f±%.5f  %.3f%s  /dgs %.3f  flip/im %.3f'%(sc[:34],app,n,best[0],best[1],vm,vs,r,mark,vm/dgm,vf/imf))
print('losses %d wins %d mean/dgs %.4f'%(loss,win,sum(ratios)/len(ratios)))
