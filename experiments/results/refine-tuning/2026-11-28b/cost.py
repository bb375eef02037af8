import csv, sys, collections, statistics
d=collections.defaultdict(lambda: collections.defaultdict(list))
for r in csv.DictReader(open(sys.argv[1])):
    if r['status']!='ok' or r['placement'] in ('none',''): continue
    k=(r['scene'][:24],r['application'],r['caches'])
    for st in ['initial_generation_s','initial_computation_s','adaptive_generation_s','adaptive_computation_s']:
        d[(k,r['placement'])][st].append(float(r[st] or 0))
keys=sorted(set(k for k,_ in d))
for k in keys:
    t={}
    for pl in ['vgc+dgs','refine']:
        t[pl]=sum(statistics.median(v) for v in d[(k,pl)].values())
    print(k,'%.3f %.3f %.3f'%(t['vgc+dgs'],t['refine'],t['refine']/t['vgc+dgs']))
