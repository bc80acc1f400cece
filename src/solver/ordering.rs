//! Bandwidth-reducing orderings of particles (Bricis B8): the half-bandwidth of a
//! numbering, Bricis's alternating column order for ring meshes (MODMSH, §5.3.4) and reverse
//! Cuthill–McKee for any mesh.

use std::collections::VecDeque;

/// Half-bandwidth of a numbering: the largest difference of the numbers of two connected
/// particles, plus one (Bricis eq. 5.3). `number[i]` is particle `i`'s number.
pub fn half_bandwidth(number: &[u32], edges: &[[u32; 2]]) -> u32 {
    edges.iter().map(|&[i, j]| number[i as usize].abs_diff(number[j as usize])).max().map_or(1, |d| d + 1)
}

/// Bricis's numbering of a ring mesh of `columns` radial lines of `rows` nodes (node
/// `ring · columns + column`): each radial line is numbered contiguously, the lines taken
/// alternately from the two ends of the ring (1, N, 2, N−1, …), so neighbours around the
/// closed ring are never more than two lines apart.
pub fn alternating_columns(columns: u32, rows: u32) -> Vec<u32> {
    let line_order: Vec<u32> = (0..columns).map(|k| if k % 2 == 0 { k / 2 } else { columns - 1 - k / 2 }).collect();
    let mut position = vec![0u32; columns as usize];
    for (place, &line) in line_order.iter().enumerate() {
        position[line as usize] = place as u32;
    }
    (0..rows * columns).map(|node| position[(node % columns) as usize] * rows + node / columns).collect()
}

/// Reverse Cuthill–McKee numbering of `count` particles connected by `edges`: breadth-first
/// from a low-degree particle, neighbours by increasing degree, then reversed. Each
/// connected component is numbered in turn. Deterministic: ties go to the lower index.
pub fn reverse_cuthill_mckee(count: usize, edges: &[[u32; 2]]) -> Vec<u32> {
    let mut neighbours = vec![Vec::new(); count];
    for &[i, j] in edges {
        neighbours[i as usize].push(j);
        neighbours[j as usize].push(i);
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    let degree: Vec<usize> = neighbours.iter().map(Vec::len).collect();
    let mut visited = vec![false; count];
    let mut sequence = Vec::with_capacity(count);
    let mut by_degree: Vec<u32> = (0..count as u32).collect();
    by_degree.sort_by_key(|&i| (degree[i as usize], i));
    for &start in &by_degree {
        if visited[start as usize] {
            continue;
        }
        visited[start as usize] = true;
        let mut queue = VecDeque::from([start]);
        while let Some(node) = queue.pop_front() {
            sequence.push(node);
            let mut next: Vec<u32> =
                neighbours[node as usize].iter().copied().filter(|&n| !visited[n as usize]).collect();
            next.sort_by_key(|&n| (degree[n as usize], n));
            for n in next {
                visited[n as usize] = true;
                queue.push_back(n);
            }
        }
    }
    let mut number = vec![0u32; count];
    for (place, &node) in sequence.iter().rev().enumerate() {
        number[node as usize] = place as u32;
    }
    number
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bricis's example (figs 5.6–5.7): 5 rings of 15 nodes, closed hoops and radial lines.
    fn ring_mesh(columns: u32, rows: u32) -> Vec<[u32; 2]> {
        let mut edges = Vec::new();
        for ring in 0..rows {
            for k in 0..columns {
                edges.push([ring * columns + k, ring * columns + (k + 1) % columns]);
                if ring + 1 < rows {
                    edges.push([ring * columns + k, (ring + 1) * columns + k]);
                }
            }
        }
        edges
    }

    #[test]
    fn bricis_ring_example_goes_from_16_to_11() {
        let edges = ring_mesh(15, 5);
        let ring_wise: Vec<u32> = (0..75).collect();
        assert_eq!(half_bandwidth(&ring_wise, &edges), 16);
        assert_eq!(half_bandwidth(&alternating_columns(15, 5), &edges), 11);
    }

    #[test]
    fn reverse_cuthill_mckee_is_a_permutation_that_narrows_the_band() {
        let edges = ring_mesh(15, 5);
        let number = reverse_cuthill_mckee(75, &edges);
        let mut sorted = number.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..75).collect::<Vec<_>>());
        // On the closed ring RCM gets 12, close to Bricis's hand-made 11 and well under 16.
        assert!(half_bandwidth(&number, &edges) <= 12, "RCM gives {}", half_bandwidth(&number, &edges));
        // A scrambled grid gets its band back.
        let grid: Vec<[u32; 2]> = (0..100u32)
            .flat_map(|i| {
                let mut e = Vec::new();
                if i % 10 < 9 {
                    e.push([i, i + 1]);
                }
                if i < 90 {
                    e.push([i, i + 10]);
                }
                e
            })
            .map(|[a, b]| [(a * 37) % 100, (b * 37) % 100])
            .collect();
        let scrambled: Vec<u32> = (0..100).collect();
        let renumbered = reverse_cuthill_mckee(100, &grid);
        assert!(half_bandwidth(&renumbered, &grid) <= 12 && half_bandwidth(&scrambled, &grid) > 50);
    }
}
