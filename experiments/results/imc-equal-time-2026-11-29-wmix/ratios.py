"""The RMSE ratio of the better many-light baseline to importance caching at equal time, to four places, for
the equal-time result folders given on the command line: as tables.md computes it (the caches' mean wall seconds
and mean RMSE over seeds; each baseline's means over seeds interpolated linearly in log-time/log-error between its
two nearest sample counts, extrapolated as error ~ t^-1/2 outside them), without its rounding to two places.
Usage: python3 ratios.py FOLDER...   (prints scene, caches, better baseline, ratio)"""
import csv,collections,math,sys
for run in sys.argv[1:]:
    rows=list(csv.DictReader(open(run+'/results.csv')))
    caches=collections.defaultdict(list); base=collections.defaultdict(list)
    for r in rows:
        if r['status']!='ok': continue
        if r['placement']=='vgc+dgs':
            caches[(r['scene'],int(r['caches']))].append((float(r['total_s']),float(r['rmse'])))
        elif r['method'].split(':')[0] in ('uniform','power'):
            base[(r['scene'],r['method'].split(':')[0],int(r['samples']))].append((float(r['total_s']),float(r['rmse'])))
    out=[]
    for (sc,k),v in sorted(caches.items()):
        t=sum(x[0] for x in v)/len(v); e=sum(x[1] for x in v)/len(v)
        best=None
        for m in ('uniform','power'):
            pts=sorted([(sum(x[0] for x in b)/len(b), sum(x[1] for x in b)/len(b)) for (s2,m2,n),b in base.items() if s2==sc and m2==m])
            if len(pts)<2: continue
            # bracket
            i=max(0,min(len(pts)-2, sum(1 for p in pts if p[0]<=t)-1))
            (t0,e0),(t1,e1)=pts[i],pts[i+1]
            if t<pts[0][0]: eb=pts[0][1]*math.sqrt(pts[0][0]/t)
            elif t>pts[-1][0]: eb=pts[-1][1]*math.sqrt(pts[-1][0]/t)
            else:
                a=(math.log(t)-math.log(t0))/(math.log(t1)-math.log(t0)); eb=math.exp(math.log(e0)+a*(math.log(e1)-math.log(e0)))
            r=eb/e
            if best is None or r<best[1]: best=(m,r)
        out.append(f"{sc} {k} {best[0]} {best[1]:.4f}")
    print(run.split('/')[-1]); print("\n".join(out))
