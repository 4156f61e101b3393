"""The derivative rules of docs/input.md, written from the docs for the sweeps' checks (not the
library's code): which multiple of which vertex makes Df(t_j).
"""


def derivative_rows(h, closed, j, rule):
    """The weights of Df(t_j) on the vertices (index → weight), Df the derivative rule of
    docs/input.md: "bessel", the derivative at t_j of the quadratic through p_{j−1}, p_j, p_{j+1}
    (at an open end, of the end quadratic at t_1 resp. t_N), or "average", ½(s_{j−1} + s_j)
    (one-sided at open ends); s_j = (p_{j+1} − p_j)/h_j; h the spans."""
    nv = len(h) if closed else len(h) + 1
    out = {}

    def slope(i, w):  # w · s_i
        a, b = i % nv, (i + 1) % nv
        out[a] = out.get(a, 0.0) - w / h[i % len(h)]
        out[b] = out.get(b, 0.0) + w / h[i % len(h)]

    if not closed and j == 0:
        if rule == "average" or nv < 3:
            slope(0, 1.0)
        else:
            h1, h2 = h[0], h[1]
            slope(0, (2 * h1 + h2) / (h1 + h2)); slope(1, -h1 / (h1 + h2))
    elif not closed and j == nv - 1:
        if rule == "average" or nv < 3:
            slope(nv - 2, 1.0)
        else:
            h1, h2 = h[nv - 3], h[nv - 2]
            slope(nv - 2, (2 * h2 + h1) / (h1 + h2)); slope(nv - 3, -h2 / (h1 + h2))
    else:
        hm, hp = h[(j - 1) % len(h)], h[j % len(h)]
        if rule == "average":
            slope(j - 1, 0.5); slope(j, 0.5)
        else:
            slope(j - 1, hp / (hm + hp)); slope(j, hm / (hm + hp))
    return out
