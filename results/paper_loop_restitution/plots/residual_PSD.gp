set terminal pngcairo size 640,420
set output 'residual_PSD.png'
set xlabel 'PSD' noenhanced
set ylabel 'measured - predicted angle [deg]'
set key outside top center horizontal noenhanced
set grid
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
set xzeroaxis lt -1
set xrange [-0.5:4-0.5]
set xtics ('1.8-2 mm' 0, '3-3.35 mm' 1, '3.5-5 mm' 2, '5.6-8 mm' 3)
set offsets 0, 0, graph 0.05, graph 0.05
plot 'residual_PSD.dat' index 0 u ($1-0.08):2:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'before', '' index 0 u ($1+0.08):3:4 w yerrorbars pt 5 lc rgb '#2471a3' t 'after'
