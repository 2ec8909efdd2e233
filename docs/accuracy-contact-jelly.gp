set terminal pngcairo size 960,640 font 'DejaVu Sans,10'
set output 'docs/accuracy-contact-jelly.png'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'wall time per simulated second [s]'
set ylabel 'centroid RMS error / body size'
set title 'jelly through contact (labels: dt; adaptive: tolerance)' noenhanced
set key outside right
set grid
plot 'docs/accuracy-contact-jelly.dat' index 0 using 2:3 with linespoints lw 2 pt 7 lc rgb '#d62728' title 'symplectic_euler' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 0 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#d62728' notitle, \
     'docs/accuracy-contact-jelly.dat' index 1 using 2:3 with linespoints lw 2 pt 7 lc rgb '#ff7f0e' title 'verlet' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 1 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#ff7f0e' notitle, \
     'docs/accuracy-contact-jelly.dat' index 2 using 2:3 with linespoints lw 2 pt 7 lc rgb '#2ca02c' title 'leapfrog' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 2 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#2ca02c' notitle, \
     'docs/accuracy-contact-jelly.dat' index 3 using 2:3 with linespoints lw 2 pt 7 lc rgb '#17becf' title 'rk4' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 3 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#17becf' notitle, \
     'docs/accuracy-contact-jelly.dat' index 4 using 2:3 with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'bs32' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 4 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#1f77b4' notitle, \
     'docs/accuracy-contact-jelly.dat' index 5 using 2:3 with linespoints lw 2 pt 7 lc rgb '#9467bd' title 'verlet_adaptive' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 5 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#9467bd' notitle, \
     'docs/accuracy-contact-jelly.dat' index 6 using 2:3 with linespoints lw 2 pt 7 lc rgb '#000000' title 'vbd' noenhanced, \
     'docs/accuracy-contact-jelly.dat' index 6 using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '#000000' notitle
