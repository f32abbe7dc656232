MeshVersionFormatted 2
Dimension 3
SolAtVertices
1
1 7
1
End
