MeshVersionFormatted 2
Dimension 3
SolAtVertices
2
3 2 4 1
1 2 3  1 2 3 4 5 6 7 8 9  0.5
-1 -2 -3  9 8 7 6 5 4 3 2 1  0.75
End
