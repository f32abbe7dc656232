MeshVersionFormatted 1
Dimension 3
SolAtVertices
3
1 1
0.5
1.5
2.5
End
