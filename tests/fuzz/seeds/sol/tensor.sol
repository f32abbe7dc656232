MeshVersionFormatted 2

Dimension 3

SolAtVertices
2
1 3
1 0.5 2 0.25 0.125 3
4 0 5 0 0 6

End
