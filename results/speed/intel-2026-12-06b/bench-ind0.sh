#!/bin/bash
# Walking-phase and early generations, before/after individual 0's early rollout, alternated.
set -u
O=/work/main/results/speed/intel-2026-12-06b
A=/work/main/target/release/esrl          # 54222e4: individual 0 rolls out as the cycles end
B=/work/exp/tgt-before/release/esrl        # ca22a13: bench es --init, individual 0 after
P=results/clock-fast/records/clock08t40-s8/policy
cd /work/main
for k in 1 2; do
  for v in after before; do
    bin=$A; [ $v = before ] && bin=$B
    /usr/bin/time -f "%e s" $bin bench es --preset walker-fast --init $P --json > $O/es-walking-$v-$k.json 2> $O/es-walking-$v-$k.time
  done
done
for v in after before; do
  bin=$A; [ $v = before ] && bin=$B
  $bin bench es --preset walker --json > $O/es-walker-$v.json
done
echo done > $O/.done
