set terminal pngcairo size 640,420
set output 'residual_plate.png'
set xlabel 'plate' noenhanced
set ylabel 'measured - predicted angle [deg]'
set key outside top center horizontal noenhanced
set grid
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
set xzeroaxis lt -1
set xrange [-0.5:2-0.5]
set xtics ('steel' 0, 'wood' 1)
set offsets 0, 0, graph 0.05, graph 0.05
plot 'residual_plate.dat' index 0 u ($1-0.08):2:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'before', '' index 0 u ($1+0.08):3:4 w yerrorbars pt 5 lc rgb '#2471a3' t 'after'
