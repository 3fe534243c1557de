set terminal pngcairo size 960,640 font 'sans,11'
set output 'pareto.png.tmp'
set title 'Error against run time per evaluation (exact solvers: error 0, time only)'
set datafile separator ','
set key outside right top
set grid
set key inside left center
set logscale xy
set xlabel 'seconds per evaluation (2 cores, llvmpipe)'
set ylabel 'median |E - V| / V'
set format y '10^{%L}'
set format x '10^{%L}'
set arrow from 0.27575637935416669, graph 0 to 0.27575637935416669, graph 1 nohead lw 2 lc rgb '#9467bd'
set label 'exact clipping' at 0.27575637935416669, graph 0.95 rotate by 90 right offset -1,0 tc rgb '#9467bd'
set arrow from 0.2657082412222222, graph 0 to 0.2657082412222222, graph 1 nohead lw 2 lc rgb '#8c564b'
set label 'exact Nef' at 0.2657082412222222, graph 0.95 rotate by 90 right offset -1,0 tc rgb '#8c564b'
set xrange [3.3333333333333335e-05:0.82826913806250013]
plot 'pareto.csv' using (strcol(1) eq 'cpu_cubemap' ? $3 : NaN):4 with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'CPU cubemap', \
 '' using (strcol(1) eq 'cpu_cubemap' ? $3 : NaN):4:(sprintf('%d', $2)) with labels offset 0,1 notitle, \
 '' using (strcol(1) eq 'gl_cubemap' ? $3 : NaN):4 with linespoints lw 2 pt 5 lc rgb '#ff7f0e' title 'GL cubemap (llvmpipe)', \
 '' using (strcol(1) eq 'gl_cubemap' ? $3 : NaN):4:(sprintf('%d', $2)) with labels offset 0,-1 tc rgb '#ff7f0e' notitle, \
 '' using (strcol(1) eq 'poly' ? $3 : NaN):4 with points pt 9 ps 2.5 lc rgb '#2ca02c' title 'polyhedral (interval width / V)'
