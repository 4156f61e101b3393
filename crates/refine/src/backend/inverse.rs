//! The inverse of one condensed point's weight, (D + ρI)⁻¹, from D's structure and without
//! cancellation: a ball's D = a I + b w wᵀ per eigenspace; a polytope's D = Σ θ_k n̂_k n̂_kᵀ in an
//! orthonormal basis built from its normals in order of decreasing θ (module docs of
//! [`super::condensed`]).

// The dense d×d kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

use banded::vector::dot;

use super::condensed::Face;

/// (D + ρ I)⁻¹ for D = a I + b w wᵀ, inverted per eigenspace: 1/(a + ρ + b|w|²) along w,
/// 1/(a + ρ) across.
pub(super) fn ball_inverse(a: f64, b: f64, w: &[f64], rho: f64, out: &mut [f64]) {
    let d = w.len();
    let w2 = dot(w, w);
    let ar = a + rho;
    let (across, along) = (1.0 / ar, 1.0 / (ar + b * w2));
    let wn = w2.sqrt();
    for i in 0..d {
        for j in 0..d {
            let id = if i == j { 1.0 } else { 0.0 };
            let uu = if wn > 0.0 {
                (w[i] / wn) * (w[j] / wn)
            } else {
                0.0
            };
            out[i * d + j] = across * (id - uu) + along * uu;
        }
    }
}

/// (ρ I + Σ_k θ_k n̂_k n̂_kᵀ)⁻¹ for unit normals, in the orthonormal basis U built by
/// Gram–Schmidt from the normals in order of decreasing θ (module docs): C = UᵀDU has each
/// generating normal's large θ on its own diagonal entry and nothing beyond it, so its
/// Cholesky factorization (largest first) subtracts no large term from a small one.
pub(super) fn faces_inverse(
    normals: &[&[f64]],
    theta: &[f64],
    rho: f64,
    d: usize,
    out: &mut [f64],
) {
    let mut order: Vec<usize> = (0..normals.len()).collect();
    order.sort_by(|&a, &b| theta[b].total_cmp(&theta[a]));
    // Orthonormal basis (rows of u) and, per face, its coordinates in that basis.
    let mut u: Vec<Vec<f64>> = Vec::with_capacity(d);
    let mut coords: Vec<Vec<f64>> = vec![vec![0.0; d]; normals.len()];
    for &k in &order {
        let n = normals[k];
        let mut c = vec![0.0; d];
        let mut r = n.to_vec();
        for (i, ui) in u.iter().enumerate() {
            let p = dot(ui, &r);
            c[i] = p;
            for (x, y) in r.iter_mut().zip(ui) {
                *x -= p * y;
            }
        }
        let rn = dot(&r, &r).sqrt();
        // A normal independent of those before (beyond rounding) opens a new direction, on
        // which it is its basis vector exactly.
        if u.len() < d && rn > 1e-8 {
            c[u.len()] = rn;
            u.push(r.iter().map(|x| x / rn).collect());
        }
        coords[k] = c;
    }
    // Complete the basis with unit vectors.
    for e in 0..d {
        if u.len() == d {
            break;
        }
        let mut r = vec![0.0; d];
        r[e] = 1.0;
        for ui in &u {
            let p = ui[e];
            for (x, y) in r.iter_mut().zip(ui) {
                *x -= p * y;
            }
        }
        let rn = dot(&r, &r).sqrt();
        if rn > 0.5 {
            u.push(r.iter().map(|x| x / rn).collect());
        }
    }
    // C = ρ I + Σ θ c cᵀ, Cholesky, and C⁻¹ column by column.
    let mut cm = vec![0.0; d * d];
    for i in 0..d {
        cm[i * d + i] = rho;
    }
    for (k, c) in coords.iter().enumerate() {
        for i in 0..d {
            if c[i] == 0.0 {
                continue;
            }
            for j in 0..d {
                cm[i * d + j] += theta[k] * c[i] * c[j];
            }
        }
    }
    let mut l = cm.clone();
    for j in 0..d {
        let mut v = l[j * d + j];
        for t in 0..j {
            v -= l[j * d + t] * l[j * d + t];
        }
        let piv = v.max(f64::MIN_POSITIVE).sqrt();
        l[j * d + j] = piv;
        for i in j + 1..d {
            let mut w = l[i * d + j];
            for t in 0..j {
                w -= l[i * d + t] * l[j * d + t];
            }
            l[i * d + j] = w / piv;
        }
    }
    let mut cinv = vec![0.0; d * d];
    let mut col = vec![0.0; d];
    for e in 0..d {
        col.fill(0.0);
        col[e] = 1.0;
        for i in 0..d {
            let mut v = col[i];
            for t in 0..i {
                v -= l[i * d + t] * col[t];
            }
            col[i] = v / l[i * d + i];
        }
        for i in (0..d).rev() {
            let mut v = col[i];
            for t in i + 1..d {
                v -= l[t * d + i] * col[t];
            }
            col[i] = v / l[i * d + i];
        }
        for i in 0..d {
            cinv[i * d + e] = col[i];
        }
    }
    // D⁻¹ = Uᵀ C⁻¹ U (rows of `u` are the basis vectors).
    for a in 0..d {
        for b in 0..d {
            let mut acc = 0.0;
            for i in 0..d {
                for j in 0..d {
                    acc += u[i][a] * cinv[i * d + j] * u[j][b];
                }
            }
            out[a * d + b] = acc;
        }
    }
}

/// [`faces_inverse`] for a compile-time d = `D` (1 to 3) into `out`, the same operations on
/// arrays (no allocation; more than [`MAX_FIXED_FACES`] faces go to [`faces_inverse`]).
pub(super) fn faces_inverse_fixed<const D: usize>(
    faces: &[Face],
    theta: &[f64],
    rho: f64,
    out: &mut [f64],
) {
    let m = faces.len();
    if m > MAX_FIXED_FACES {
        let normals: Vec<&[f64]> = faces.iter().map(|f| f.normal.as_slice()).collect();
        return faces_inverse(&normals, theta, rho, D, out);
    }
    let mut order = [0usize; MAX_FIXED_FACES];
    for (k, o) in order[..m].iter_mut().enumerate() {
        *o = k;
    }
    order[..m].sort_by(|&a, &b| theta[b].total_cmp(&theta[a]));
    let mut u = [[0.0f64; D]; D];
    let mut ulen = 0;
    let mut coords = [[0.0f64; D]; MAX_FIXED_FACES];
    for &k in &order[..m] {
        let n = &faces[k].normal;
        let mut c = [0.0; D];
        let mut r: [f64; D] = std::array::from_fn(|e| n[e]);
        for (i, ui) in u[..ulen].iter().enumerate() {
            let mut p = 0.0;
            for e in 0..D {
                p += ui[e] * r[e];
            }
            c[i] = p;
            for e in 0..D {
                r[e] -= p * ui[e];
            }
        }
        let mut rr = 0.0;
        for e in 0..D {
            rr += r[e] * r[e];
        }
        let rn = rr.sqrt();
        if ulen < D && rn > 1e-8 {
            c[ulen] = rn;
            u[ulen] = std::array::from_fn(|e| r[e] / rn);
            ulen += 1;
        }
        coords[k] = c;
    }
    for e in 0..D {
        if ulen == D {
            break;
        }
        let mut r = [0.0; D];
        r[e] = 1.0;
        for ui in &u[..ulen] {
            let p = ui[e];
            for k in 0..D {
                r[k] -= p * ui[k];
            }
        }
        let mut rr = 0.0;
        for k in 0..D {
            rr += r[k] * r[k];
        }
        let rn = rr.sqrt();
        if rn > 0.5 {
            u[ulen] = std::array::from_fn(|k| r[k] / rn);
            ulen += 1;
        }
    }
    let mut cm = [[0.0f64; D]; D];
    for i in 0..D {
        cm[i][i] = rho;
    }
    for (k, c) in coords[..m].iter().enumerate() {
        for i in 0..D {
            if c[i] == 0.0 {
                continue;
            }
            for j in 0..D {
                cm[i][j] += theta[k] * c[i] * c[j];
            }
        }
    }
    let mut l = cm;
    for j in 0..D {
        let mut v = l[j][j];
        for t in 0..j {
            v -= l[j][t] * l[j][t];
        }
        let piv = v.max(f64::MIN_POSITIVE).sqrt();
        l[j][j] = piv;
        for i in j + 1..D {
            let mut w = l[i][j];
            for t in 0..j {
                w -= l[i][t] * l[j][t];
            }
            l[i][j] = w / piv;
        }
    }
    let mut cinv = [[0.0f64; D]; D];
    for e in 0..D {
        let mut col = [0.0; D];
        col[e] = 1.0;
        for i in 0..D {
            let mut v = col[i];
            for t in 0..i {
                v -= l[i][t] * col[t];
            }
            col[i] = v / l[i][i];
        }
        for i in (0..D).rev() {
            let mut v = col[i];
            for t in i + 1..D {
                v -= l[t][i] * col[t];
            }
            col[i] = v / l[i][i];
        }
        for i in 0..D {
            cinv[i][e] = col[i];
        }
    }
    for a in 0..D {
        for b in 0..D {
            let mut acc = 0.0;
            for i in 0..D {
                for j in 0..D {
                    acc += u[i][a] * cinv[i][j] * u[j][b];
                }
            }
            out[a * D + b] = acc;
        }
    }
}

/// Faces per point that [`faces_inverse_fixed`] keeps on the stack.
const MAX_FIXED_FACES: usize = 16;

#[cfg(test)]
mod tests {
    use super::{ball_inverse, faces_inverse};

    fn matmul(a: &[f64], b: &[f64], d: usize) -> Vec<f64> {
        let mut c = vec![0.0; d * d];
        for i in 0..d {
            for j in 0..d {
                c[i * d + j] = (0..d).map(|k| a[i * d + k] * b[k * d + j]).sum();
            }
        }
        c
    }

    /// The structured inverses invert: (D + ρI) · inverse = I on well-conditioned cases.
    #[test]
    fn structured_inverses_invert() {
        let d = 3;
        let w = [0.3, -0.4, 0.5];
        let mut inv = vec![0.0; 9];
        ball_inverse(2.0, 4.0, &w, 0.1, &mut inv);
        let mut m = vec![0.0; 9];
        for i in 0..d {
            for j in 0..d {
                m[i * d + j] = 4.0 * w[i] * w[j] + if i == j { 2.1 } else { 0.0 };
            }
        }
        let id = matmul(&m, &inv, d);
        for i in 0..d {
            for j in 0..d {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((id[i * d + j] - want).abs() < 1e-12, "{id:?}");
            }
        }
        let n1 = [0.6, 0.8, 0.0];
        let n2 = [0.0, 0.6, 0.8];
        let theta = [3.0, 0.5];
        faces_inverse(&[&n1, &n2], &theta, 0.2, d, &mut inv);
        for i in 0..d {
            for j in 0..d {
                m[i * d + j] = theta[0] * n1[i] * n1[j]
                    + theta[1] * n2[i] * n2[j]
                    + if i == j { 0.2 } else { 0.0 };
            }
        }
        let id = matmul(&m, &inv, d);
        for i in 0..d {
            for j in 0..d {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((id[i * d + j] - want).abs() < 1e-12, "{id:?}");
            }
        }
    }

    /// The fixed-size inverse of faces does what the general one does, to the last bit.
    #[test]
    fn the_fixed_size_faces_inverse_is_the_general_one() {
        let face = |n: &[f64]| {
            let l = n.iter().map(|x| x * x).sum::<f64>().sqrt();
            super::Face {
                normal: n.iter().map(|x| x / l).collect(),
                offset: 0.0,
                norm: l,
            }
        };
        let cases: Vec<(Vec<super::Face>, Vec<f64>)> = vec![
            (
                vec![face(&[1.0, 0.2]), face(&[-0.3, 1.0]), face(&[0.7, -0.7])],
                vec![3.0, 1e-6, 2e8],
            ),
            (vec![face(&[1.0, 0.0]), face(&[-1.0, 0.0])], vec![1e12, 0.5]),
            (
                vec![
                    face(&[1.0, 0.2, 0.1]),
                    face(&[0.0, 1.0, 0.3]),
                    face(&[0.2, -0.1, 1.0]),
                    face(&[-1.0, 0.0, 0.0]),
                ],
                vec![1e-3, 7.0, 1e9, 0.0],
            ),
        ];
        for (faces, theta) in cases {
            let d = faces[0].normal.len();
            let normals: Vec<&[f64]> = faces.iter().map(|f| f.normal.as_slice()).collect();
            let mut a = vec![0.0; d * d];
            faces_inverse(&normals, &theta, 1e-9, d, &mut a);
            let mut b = vec![0.0; d * d];
            match d {
                2 => super::faces_inverse_fixed::<2>(&faces, &theta, 1e-9, &mut b),
                _ => super::faces_inverse_fixed::<3>(&faces, &theta, 1e-9, &mut b),
            }
            assert_eq!(
                a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                "{a:?} vs {b:?}"
            );
        }
    }

    /// With one face stiff (θ = 1e20) and ρ = 1e-13 the inverse across that face is 1/ρ-scale
    /// and exact to rounding (a dense inverse loses it completely: the determinant cancels).
    #[test]
    fn a_stiff_face_does_not_swamp_the_small_directions() {
        let d = 2;
        let s = 0.5f64.sqrt();
        let n1 = [s, s];
        let n2 = [s, -s];
        let mut inv = vec![0.0; 4];
        faces_inverse(&[&n1, &n2], &[1e20, 1e-3], 1e-13, d, &mut inv);
        // Across n1 (along n2): 1/(1e-13 + 1e-3); along n1: 1/(1e20 + 1e-13).
        let along_n2: f64 = (0..d)
            .map(|i| (0..d).map(|j| n2[i] * inv[i * d + j] * n2[j]).sum::<f64>())
            .sum();
        let want = 1.0 / (1e-13 + 1e-3);
        assert!(
            (along_n2 - want).abs() <= 1e-12 * want,
            "{along_n2} vs {want}"
        );
        let along_n1: f64 = (0..d)
            .map(|i| (0..d).map(|j| n1[i] * inv[i * d + j] * n1[j]).sum::<f64>())
            .sum();
        assert!(
            (along_n1 - 1e-20).abs() <= 1e-3 * 1e-20 + 1e-16 * want,
            "{along_n1}"
        );
    }
}
