# Charts of the island benchmark, drawn by bench_islands:
#   gnuplot -e "dir='docs/bench'" bench/islands/charts.gp
# Reads islands_map.csv and islands_scaling.csv in dir, writes PNG files next to them.
set terminal pngcairo size 1000,600 noenhanced font ",10"
set datafile separator ","
data_lines(f) = system(sprintf("awk 'NR > 1 { n++ } END { print n + 0 }' '%s' 2>/dev/null || echo 0", f)) + 0

map = dir."/islands_map.csv"
if (data_lines(map) > 0) {
  set output dir."/islands_map.png"
  set title "Conditional objects: runs with every parameter within 1 % (of 10), at equal evaluation budgets"
  set style data histograms
  set style histogram clustered gap 1
  set style fill solid 0.8 border -1
  set yrange [0:10.5]
  set ylabel "successes"
  set xlabel "cable types"
  set key top right
  methods = "default one_300 islands islands_ring islands_alone islands_third sade"
  plot for [m in methods] sprintf("< awk -F, '$2 == \"%s\" { print $1 \",\" $3 }' '%s'", m, map) \
       using 2:xtic(1) title m, \
       sprintf("< awk -F, 'NR > 1 && $2 == \"default\" { print $1 \",\" $7 }' '%s'", map) \
       using 0:2 with linespoints lw 2 pt 7 lc rgb "black" title "interval middles within 1 % (the limit)"
  unset style
}

scaling = dir."/islands_scaling.csv"
if (data_lines(scaling) > 0) {
  reset
  set terminal pngcairo size 1000,600 noenhanced font ",10"
  set datafile separator ","
  set output dir."/islands_scaling.png"
  set title "Cable objects (5 cable types): median time to every parameter within 1 %, 2 cores"
  set xlabel "islands (threads = min(islands, 2))"
  set ylabel "median wall time to target [s]"
  set y2label "evaluations/s per island"
  set ytics nomirror
  set y2tics
  set xtics (1, 2, 4)
  set key top right
  plot scaling using 1:5 every ::1 with linespoints lw 2 pt 7 title "time to target", \
       scaling using 1:7 every ::1 axes x1y2 with linespoints lw 2 pt 5 dt 2 title "throughput per island"
}
