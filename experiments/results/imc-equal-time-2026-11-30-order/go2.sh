#!/bin/bash
cd /work/scratch/et
for x in "C2 cor" "B1 bath" "S2 sib" "C3 cor"; do set -- $x
  echo "$1 start $(date -u +%T)"
  ./cachert-e8562fa experiment $2.toml --out $1 --nthreads 2 > $1.log 2>&1
  echo "$1 end $(date -u +%T) rc=$?"
done
