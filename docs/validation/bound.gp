set terminal pngcairo size 960,640 font 'sans,11'
set output 'bound.png.tmp'
set title 'Stated bound B(m) against normalised errors |E - V| / vol(O)'
set datafile separator ','
set key outside right top
set grid
set logscale xy
set xlabel 'cubemap resolution m'
set ylabel '|E - V| / vol(O)'
set xtics (4,8,16,32,64,128,256)
set format y '10^{%L}'
set key outside right top
set datafile missing 'nan'
B(x) = 0.27036104623737162*x**-2.0020409795687368
plot 'evaluations.csv' using (strcol(2) eq 'fit' ? $6*(1+0.03*($4-5)) : NaN):($10 > 0 ? $10 : NaN) with points pt 7 ps 0.4 lc rgb '#1f77b4' title 'fit corpus', \
 '' using (strcol(2) eq 'held_out' ? $6*(1.12+0.03*($4-5)) : NaN):($10 > 0 ? $10 : NaN) with points pt 6 ps 0.5 lc rgb '#ff7f0e' title 'held-out corpus', \
 B(x) with lines lw 2 lc rgb 'black' title 'B(m)', \
 'error_by_m.csv' using (strcol(1) eq 'cpu' ? $2 : NaN):13 with linespoints dt 3 lc rgb '#d62728' title 'rigorous R(m)/vol(O), median'
