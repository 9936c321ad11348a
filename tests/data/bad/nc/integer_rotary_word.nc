%
O1002 (B indexed without a decimal point)
G90 G21
G00 X-390.0000 Y0.0000 Z-112.2605 B0.0000 C0.0000
G00 B90
M30
%
