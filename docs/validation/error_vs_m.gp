set terminal pngcairo size 960,640 font 'sans,11'
set output 'error_vs_m.png.tmp'
set title 'Relative error of the cubemap estimate against exact OBV'
set datafile separator ','
set key outside right top
set grid
set logscale xy
set xlabel 'cubemap resolution m'
set ylabel '|E - V| / V'
set xtics (4,8,16,32,64,128,256)
set format y '10^{%L}'
plot 'error_by_m.csv' using (strcol(1) eq 'cpu' ? $2 : NaN):4 with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'CPU median', \
 '' using (strcol(1) eq 'cpu' ? $2 : NaN):5 with linespoints lw 2 pt 5 lc rgb '#2ca02c' title 'CPU p95', \
 '' using (strcol(1) eq 'cpu' ? $2 : NaN):6 with linespoints lw 2 pt 9 lc rgb '#d62728' title 'CPU max', \
 '' using (strcol(1) eq 'gl' ? $2 : NaN):4 with points pt 6 ps 2 lc rgb '#1f77b4' title 'GL median', \
 '' using (strcol(1) eq 'gl' ? $2 : NaN):5 with points pt 4 ps 2 lc rgb '#2ca02c' title 'GL p95', \
 '' using (strcol(1) eq 'gl' ? $2 : NaN):6 with points pt 8 ps 2 lc rgb '#d62728' title 'GL max', \
 0.00012875935799009378*(x/32.0)**-2 with lines dt 2 lc rgb 'gray40' title 'm^{-2} (through the CPU median at 32)'
