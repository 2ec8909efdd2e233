set terminal pngcairo size 960,640 font 'DejaVu Sans,10'
set output 'accuracy-gas.png'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'run time per simulated second [s]'
set ylabel 'RMS position error / body size'
set title 'gas: error against run time (labels: dt)' noenhanced
set key outside right
set grid
plot 'accuracy-gas.dat' index 0 using 2:3 with linespoints lw 2 pt 7 lc rgb '#d62728' title 'explicit_euler' noenhanced, \
     'accuracy-gas.dat' index 0 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#d62728' notitle, \
     'accuracy-gas.dat' index 1 using 2:3 with linespoints lw 2 pt 7 lc rgb '#ff7f0e' title 'symplectic_euler' noenhanced, \
     'accuracy-gas.dat' index 1 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#ff7f0e' notitle, \
     'accuracy-gas.dat' index 2 using 2:3 with linespoints lw 2 pt 7 lc rgb '#2ca02c' title 'verlet' noenhanced, \
     'accuracy-gas.dat' index 2 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#2ca02c' notitle, \
     'accuracy-gas.dat' index 3 using 2:3 with linespoints lw 2 pt 7 lc rgb '#17becf' title 'leapfrog' noenhanced, \
     'accuracy-gas.dat' index 3 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#17becf' notitle, \
     'accuracy-gas.dat' index 4 using 2:3 with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'rk4' noenhanced, \
     'accuracy-gas.dat' index 4 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#1f77b4' notitle, \
     'accuracy-gas.dat' index 5 using 2:3 with linespoints lw 2 pt 7 lc rgb '#9467bd' title 'backward_euler' noenhanced, \
     'accuracy-gas.dat' index 5 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#9467bd' notitle
