set terminal pngcairo size 960,640 font 'sans,11'
set output 'upper_bound.png.tmp'
set title 'Gap (sum OBV - OMV) / OMV per layer, exact'
set datafile separator ','
set key outside right top
set grid
set xlabel 'layer (level)'
set xtics 1
set ylabel '(sum OBV - OMV) / OMV'
set datafile separator ','
plot 'upper_bound.csv' using (strcol(1) eq 'dino' && strcol(2) eq 'obbtree' ? $3 : NaN):10 with linespoints lw 2 pt 5 title 'dino obbtree', \
 'upper_bound.csv' using (strcol(1) eq 'dino' && strcol(2) eq 'variational' ? $3 : NaN):10 with linespoints lw 2 pt 7 title 'dino variational', \
 'upper_bound.csv' using (strcol(1) eq 'elephant' && strcol(2) eq 'obbtree' ? $3 : NaN):10 with linespoints lw 2 pt 5 title 'elephant obbtree', \
 'upper_bound.csv' using (strcol(1) eq 'elephant' && strcol(2) eq 'variational' ? $3 : NaN):10 with linespoints lw 2 pt 7 title 'elephant variational', \
 'upper_bound.csv' using (strcol(1) eq 'knot1' && strcol(2) eq 'obbtree' ? $3 : NaN):10 with linespoints lw 2 pt 5 title 'knot1 obbtree', \
 'upper_bound.csv' using (strcol(1) eq 'knot1' && strcol(2) eq 'variational' ? $3 : NaN):10 with linespoints lw 2 pt 7 title 'knot1 variational'
