# Charts of the peer benchmark, drawn by scripts/bench:
#   gnuplot -e "dir='docs/bench'; scenes='paper_object ...'" bench/peers/charts.gp
# Reads the CSV files bench_peers wrote into dir, writes PNG files next to them.
set terminal pngcairo size 1200,800 noenhanced font ",10"
set datafile separator ","
set datafile missing "n/a"
methods = "es_local es_global cmaes sade bobyqa lm lls es_early es_lm default sade_final"
# the methods of the stability map (es_early runs in the speed-accuracy part only; sade_final on
# the conditional axis only)
map_methods = "10 1 2 3 4 5 6 7 9 11"
# the methods drawn as curves in the speed-accuracy charts (lls: one point)
curve_methods = "10 1 2 3 4 5 6 8 9"
set style line 1 lc rgb "#1f77b4" lw 2 pt 7
set style line 2 lc rgb "#aec7e8" lw 2 pt 7
set style line 3 lc rgb "#d62728" lw 2 pt 5
set style line 4 lc rgb "#ff9896" lw 2 pt 5
set style line 5 lc rgb "#2ca02c" lw 2 pt 9
set style line 6 lc rgb "#9467bd" lw 2 pt 11
set style line 7 lc rgb "#000000" lw 2 pt 13 ps 2
set style line 8 lc rgb "#ff7f0e" lw 2 dt 2 pt 7
set style line 9 lc rgb "#17becf" lw 3 pt 7
set style line 10 lc rgb "#8c564b" lw 4 pt 15 ps 1.5
set style line 11 lc rgb "#ff9896" lw 2 dt 3 pt 4
# Data lines in a CSV file (0 when it is missing): a chart whose part did not run is skipped.
data_lines(f) = system(sprintf("awk 'NR > 1 { n++ } END { print n + 0 }' '%s' 2>/dev/null || echo 0", f)) + 0
floor_err = 1e-7
clip(x) = (x < floor_err ? floor_err : x)

# ---------------------------------------------------------------- (a) speed against accuracy
trace = dir."/speed_accuracy_trace.csv"
runs = dir."/speed_accuracy_runs.csv"
do for [scene in scenes] {
  set output dir."/speed_accuracy_".scene.".png"
  set multiplot layout 2,2 title scene.": best-so-far parameter error (seed 1; LLS = one solve, black point)"
  set logscale xy
  set format y "%.0e"
  set key bottom left
  do for [col in "8 7"] {
    errname = (col eq "8" ? "max" : "median")
    rcol = (col eq "8" ? 9 : 8)
    set xlabel "cost evaluations"; set ylabel errname." parameter error [%]"
    plot for [k in curve_methods] trace using (strcol(1) eq scene && strcol(2) eq word(methods,k+0) && $3==1 ? $4 : 1/0):(clip(column(col+0))) \
           with steps ls k+0 title word(methods,k+0), \
         runs using (strcol(1) eq scene && strcol(2) eq "lls" && $3==1 ? 1 : 1/0):(clip(column(rcol))) with points ls 7 title "lls"
    set xlabel "wall time [s]"
    plot for [k in curve_methods] trace using (strcol(1) eq scene && strcol(2) eq word(methods,k+0) && $3==1 ? $5 : 1/0):(clip(column(col+0))) \
           with steps ls k+0 title word(methods,k+0), \
         runs using (strcol(1) eq scene && strcol(2) eq "lls" && $3==1 ? ($7 > 1e-5 ? $7 : 1e-5) : 1/0):(clip(column(rcol))) with points ls 7 title "lls"
  }
  unset multiplot
  unset logscale
  set format y "%g"
}

# ---------------------------------------------------------------- (b) stability map
if (data_lines(dir."/stability_rates.csv") > 0) {
  rates = dir."/stability_rates.csv"
  set output dir."/stability_map.png"
  set multiplot layout 2,3 title "success rate (all parameters within 1 %) per setting; one line per method"
  set yrange [-0.05:1.05]
  set key top right font ",8"
  set ylabel "success rate"
  # Each curve reads only its own rows (through awk), so its points join into a line; the x tics
  # (the settings) come from the first row of each setting, whichever methods ran.
  rows(axis, m) = sprintf("< awk -F, -v a='%s' -v m='%s' '$1 == a && $4 == m' '%s'", axis, m, rates)
  settings(axis) = sprintf("< awk -F, -v a='%s' '$1 == a && !seen[$2]++' '%s'", axis, rates)
  # The axes the map ran (in the file's order), so a partial run (--axes) draws its own.
  map_axes = system(sprintf("awk -F, 'NR > 1 && !seen[$1]++ { printf \"%%s \", $1 }' '%s'", rates))
  do for [axis in map_axes] {
    set xlabel axis
    set xrange [-0.3:*]
    plot settings(axis) using 3:(1/0):xtic(2) notitle, \
         for [k in map_methods] rows(axis, word(methods,k+0)) using ($3 + ((k+0)%10-4)*0.02):7 \
         with linespoints ls k+0 title word(methods,k+0)
  }
  unset multiplot
  set xrange [*:*]; set yrange [*:*]
}

# ---------------------------------------------------------------- (c) long rollouts
if (data_lines(dir."/stability_rates.csv") > 0 && data_lines(dir."/rollout.csv") > 0) {
  set output dir."/rollout.png"
  set multiplot layout 1,2 title "(c) identified models whose long rollout (10x the window) stays bounded"
  set style data histograms
  set style histogram clustered gap 1
  set style fill solid 0.8 border -1
  set yrange [0:1.05]
  set ylabel "bounded share"
  set xlabel ""
  set key top right
  plot dir."/rollout.csv" using 4:xtic(1) title "stability-map runs", '' using 7 title "speed-accuracy runs"
  set style data linespoints
  set xlabel "omega_max * h (explicit limit 2)"
  set xrange [-0.3:*]
  if (strstrt(map_axes, "omega_h") > 0) {
    plot settings("omega_h") using 3:(1/0):xtic(2) notitle, \
         for [k in map_methods] rows("omega_h", word(methods,k+0)) using ($3 + ((k+0)%10-4)*0.02):8 \
         with linespoints ls k+0 title word(methods,k+0)
  }
  unset multiplot
  set xrange [*:*]; set yrange [*:*]
}

# ---------------------------------------------------------------- (d) scaling
if (data_lines(dir."/scaling.csv") > 0) {
  set output dir."/scaling.png"
  set multiplot layout 1,2 title "(d) es_local: time per generation (100 children) on spring sheets, 10 frames"
  set logscale xy
  set xlabel "particles"; set ylabel "s per generation"; set key top left
  # Each series reads only its own rows (through awk) so that its points join into a line.
  threads_rows(t) = sprintf("< awk -F, 'NR > 1 && $5 == %d' '%s'", t, dir."/scaling.csv")
  plot threads_rows(1) using 1:6 with linespoints ls 1 title "1 thread", \
       threads_rows(2) using 1:6 with linespoints ls 3 title "2 threads"
  unset logscale y
  set logscale x
  set yrange [0:1.25]; set ylabel "parallel efficiency t1 / (2 t2)"
  plot threads_rows(2) using 1:8 with linespoints ls 3 title "2 threads", 0.85 with lines dt 2 lc rgb "gray" title "85 % target"
  unset multiplot
  unset logscale; set yrange [*:*]
}

# ---------------------------------------------------------------- generations against unknowns
if (data_lines(dir."/unknowns_generations.csv") > 0) {
  set output dir."/generations_vs_unknowns.png"
  set terminal pngcairo size 800,500 noenhanced font ",10"
  set logscale x
  set xlabel "unknowns"; set ylabel "median generations to max error < 1 % (converged seeds)"
  set key top left
  plot for [k in "1 2 3 4 9"] dir."/unknowns_generations.csv" using (strcol(2) eq word(methods,k+0) ? $1 : 1/0):5 \
       with linespoints ls k+0 title word(methods,k+0)
}


# ---------------------------------------------------------------- noise: error against the bound
if (data_lines(dir."/efficiency.csv") > 0) {
  set output dir."/efficiency.png"
  set terminal pngcairo size 900,600 noenhanced font ",10"
  set logscale xy
  set format y "%g"
  set format x "%.0e"
  set xrange [*:*]; set yrange [*:*]
  set xlabel "marker noise std [m]"
  set ylabel "median over seeds of the median over parameters of |error| / Cramer-Rao bound"
  set title "efficiency against noise (an efficient estimator: about 0.67, the median of |N(0,1)|)"
  set key top left
  eff_rows(m) = sprintf("< awk -F, -v m='%s' 'NR > 1 && $2 == m' '%s'", m, dir."/efficiency.csv")
  plot for [k in map_methods] eff_rows(word(methods,k+0)) using 1:9 with linespoints ls k+0 title word(methods,k+0), \
       0.674 with lines dt 2 lc rgb "gray" title "0.67 (efficient)"
}
