// cgal_mesh.cpp - test data: a ball in a ball (two regions) meshed by CGAL's Mesh_3
// and written by CGAL's own writers (Medit, VTU); built and run by make.sh, not by
// the project's build.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/File_medit.h>
#include <CGAL/IO/output_to_vtu.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>
#include <fstream>
#include <functional>
#include <iostream>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Labeled_mesh_domain_3<K> Domain;
typedef CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr> C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Criteria;

// The subdomain of a point: 1 in a small ball (radius 0.18 around (0.5, 0.5,
// 0.72)), 2 in the rest of the ball of radius 0.5 around the centre of the unit
// box, 0 outside. The small ball is off the centre: Mesh_3 finds its first
// surface points on rays from the bounding sphere's centre, and from inside the
// small ball it finds only the small ball's surface (the shell is never meshed).
static int label(const Point &p)
{
    double r2 = CGAL::to_double(CGAL::squared_distance(p, Point(0.5, 0.5, 0.72)));
    double q2 = CGAL::to_double(CGAL::squared_distance(p, Point(0.5, 0.5, 0.5)));
    return r2 < 0.18 * 0.18 ? 1 : q2 < 0.25 ? 2 : 0;
}

int main()
{
    namespace params = CGAL::parameters;
    Domain domain(std::function<int(const Point &)>(label),
                  K::Sphere_3(Point(0.5, 0.5, 0.5), 0.36),
                  params::relative_error_bound = 1e-8);
    Criteria criteria(params::facet_angle = 25, params::facet_size = 0.12,
                      params::facet_distance = 0.005, params::cell_radius_edge_ratio = 2.5,
                      params::cell_size = 0.14);
    // the defaults: perturbation and sliver exudation, CGAL's default random seed
    C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria);
    std::cerr << c3t3.triangulation().number_of_vertices() << " vertices, "
              << c3t3.number_of_cells_in_complex() << " tets, "
              << c3t3.number_of_facets_in_complex() << " surface facets\n";
    // Medit as Mesh_3's examples write it (no rebinding, no patches: each
    // surface facet twice, once with the label of each side) and with
    // rebinding and patch labels (each facet once)
    std::ofstream twice("cgal.mesh");
    CGAL::IO::output_to_medit(twice, c3t3);
    std::ofstream patches("cgal_patches.mesh");
    CGAL::IO::output_to_medit(patches, c3t3, true, true);
    std::ofstream bin("cgal.vtu", std::ios::binary);
    CGAL::IO::output_to_vtu(bin, c3t3, CGAL::IO::BINARY);
    std::ofstream ascii("cgal_ascii.vtu");
    CGAL::IO::output_to_vtu(ascii, c3t3, CGAL::IO::ASCII);
    return twice && patches && bin && ascii ? 0 : 1;
}
