MeshVersionFormatted 2
Dimension 3
SolAtVertices
2
1 1
1
2
3
End
