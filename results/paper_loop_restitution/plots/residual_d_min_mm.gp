set terminal pngcairo size 640,420
set output 'residual_d_min_mm.png'
set xlabel 'd_min_mm' noenhanced
set ylabel 'measured - predicted angle [deg]'
set key outside top center horizontal noenhanced
set grid
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
set xzeroaxis lt -1
plot 'residual_d_min_mm.dat' index 0 u ($1):2:4 w yerrorbars pt 6 lc rgb '#c0392b' t 'before, PSD 1.8-2 mm', '' index 0 u ($1):3:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'after, PSD 1.8-2 mm', 'residual_d_min_mm.dat' index 1 u ($1):2:4 w yerrorbars pt 6 lc rgb '#2471a3' t 'before, PSD 3-3.35 mm', '' index 1 u ($1):3:4 w yerrorbars pt 7 lc rgb '#2471a3' t 'after, PSD 3-3.35 mm', 'residual_d_min_mm.dat' index 2 u ($1):2:4 w yerrorbars pt 6 lc rgb '#27ae60' t 'before, PSD 3.5-5 mm', '' index 2 u ($1):3:4 w yerrorbars pt 7 lc rgb '#27ae60' t 'after, PSD 3.5-5 mm', 'residual_d_min_mm.dat' index 3 u ($1):2:4 w yerrorbars pt 6 lc rgb '#8e44ad' t 'before, PSD 5.6-8 mm', '' index 3 u ($1):3:4 w yerrorbars pt 7 lc rgb '#8e44ad' t 'after, PSD 5.6-8 mm'
