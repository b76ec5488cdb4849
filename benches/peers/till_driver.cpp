// Side-by-side driver (tdcr's own code): cases S and H of docs/model.md solved with the
// building blocks of John Till's ContinuumRobotExamples (header-only C++, MIT): its RK4
// integrator `ode4` and its Levenberg-Marquardt `solveLevenbergMarquardt` with a
// forward-difference Jacobian, shooting on the base force and moment as in the peer's
// 01_Statics/05_Tendon_Robot example. None of the peer's code is in this file; it is compiled
// against a checkout given on the command line (benches/peers/run.sh).
//
// The model is the one tdcr solves (docs/model.md): Rucker and Webster's tendon-coupled
// Cosserat rod, general routing r(s) with r' and r'' (the peer's example has straight
// tendons only), self weight, a tip force at the centreline and the tendon forces at the tip.
// Only tendons under tension are integrated (the slack ones add nothing): the peer's best case.
//
// Output, one line per case and start: case, start, RK4 steps, median thread CPU time of a
// solve (ms), residual evaluations of the last solve, tip error against the reference tip (m).
#include <commonmath.h>
#include <convexoptimization.h>
#include <numericalintegration.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

using namespace ContinuumRobotLibrary;

// Prototype of docs/reference.md (SI units).
static const double L = 0.242;            // backbone length (m)
static const double radius = 0.0004;      // backbone radius (m)
static const double E = 210e9;            // Young's modulus (Pa)
static const double nu = 0.3125;          // Poisson's ratio
static const double Gmod = E / (2 * (1 + nu));
static const double weight = 0.47;        // self weight per length (N/m), along world -z
static const double offset = 0.008;       // tendon offset (m)

static const double area = pi * radius * radius;
static const double I = pi * std::pow(radius, 4) / 4;
static const DiagonalMatrix<double, 3> Kse(Gmod * area, Gmod * area, E * area);
static const DiagonalMatrix<double, 3> Kbt(E * I, E * I, Gmod * 2 * I);
static const Vector3d f_e(0, 0, -weight);  // distributed force (N/m), world frame

// The case being solved: one tensioned tendon (straight at (8, 0) mm, or a helix of one turn
// at 8 mm), its tension, the tip force and the base rotation.
static bool helical = false;
static double tension = 0;
static Vector3d tip_force = Vector3d::Zero();
static Matrix3d R0;
static long evaluations = 0;

// Tendon offset r(s) and its derivatives in the body frame (m, 1, 1/m).
static void routing(double s, Vector3d& r, Vector3d& r_s, Vector3d& r_ss) {
    if (!helical) {
        r = Vector3d(offset, 0, 0);
        r_s.setZero();
        r_ss.setZero();
        return;
    }
    const double w = 2 * pi / L, a = w * s;
    r = offset * Vector3d(std::cos(a), std::sin(a), 0);
    r_s = offset * w * Vector3d(-std::sin(a), std::cos(a), 0);
    r_ss = -w * w * r;
}

// y = (p, R column-major, v, u); y_s = dy/ds.
static void rod_ode(VectorXd& y_s, double s, VectorXd& y) {
    Matrix3d R = Map<Matrix3d>(&y[3]);
    Vector3d v = Map<Vector3d>(&y[12]);
    Vector3d u = Map<Vector3d>(&y[15]);
    Vector3d r, r_s, r_ss;
    routing(s, r, r_s, r_ss);

    Vector3d pb_s = u.cross(r) + r_s + v;
    double norm = pb_s.norm();
    Matrix3d A = -hat_squared(pb_s) * (tension / (norm * norm * norm));
    Matrix3d G = -hat_postmultiply(A, r);
    Vector3d a = A * (u.cross(pb_s) + u.cross(r_s) + r_ss);
    Vector3d b = r.cross(a);
    Matrix3d H = hat_premultiply(r, G);

    Matrix6d K;
    K << Matrix3d(Kse) + A, G, G.transpose(), Matrix3d(Kbt) + H;
    Vector3d nb = Kse * (v - Vector3d::UnitZ());
    Vector3d mb = Kbt * u;
    Vector6d rhs;
    rhs << -u.cross(nb) - transposeMultiply(R, f_e) - a, -u.cross(mb) - v.cross(nb) - b;

    Map<Vector3d> p_s(&y_s[0]);
    Map<Matrix3d> R_s(&y_s[3]);
    Map<Vector6d> vu_s(&y_s[12]);
    p_s = R * v;
    R_s = hat_postmultiply(R, u);
    vu_s = K.selfadjointView<Eigen::Upper>().llt().solve(rhs);
}

static MatrixXd Y;

// Distal wrench error of the guess (n_b(0), u(0)), integrated with N - 1 RK4 steps.
template <int N>
static VectorXd shooting(VectorXd guess) {
    ++evaluations;
    Vector3d nb0 = guess.segment<3>(0);
    Vector3d v0 = Kse.inverse() * nb0 + Vector3d::UnitZ();
    Vector3d u0 = guess.segment<3>(3);
    VectorXd y0(18);
    y0 << Vector3d::Zero(), Map<VectorXd>(R0.data(), 9), v0, u0;
    Y = ode4<rod_ode, N>(y0, 0, L);

    Vector3d vL = Y.block<3, 1>(12, N - 1);
    Vector3d uL = Y.block<3, 1>(15, N - 1);
    Matrix3d RL = Map<Matrix3d>(&Y(3, N - 1));
    Vector3d r, r_s, r_ss;
    routing(L, r, r_s, r_ss);
    Vector3d pb_s = uL.cross(r) + r_s + vL;
    Vector3d Fb = -tension * pb_s.normalized();
    Vector3d force = -(Kse * (vL - Vector3d::UnitZ())) + Fb + RL.transpose() * tip_force;
    Vector3d moment = -(Kbt * uL) + r.cross(Fb);
    Vector6d out;
    out << force, moment;
    return out;
}

static double thread_cpu_ms() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

struct Settings {
    double stop;   // LM stop: sum of squares of the distal wrench error
};

template <int N>
static VectorXd solve(const VectorXd& guess, const Settings& settings) {
    // The arguments after the stop are the peer example's own (500 iterations, damping 1e-2,
    // adaptation 0.5, difference increment 1e-7 relative with floor 1e-9).
    return solveLevenbergMarquardt<shooting<N>>(guess, settings.stop, 500, 1e-2, 0.5, 1e-7, 1e-9);
}

template <int N>
static void run_case(const char* name, const Vector3d& reference, double tension_full, int repeats,
                     const Settings& settings) {
    const int steps = N - 1;
    for (int warm = 0; warm < 2; ++warm) {
        std::vector<double> times;
        VectorXd solution;
        long evals = 0;
        for (int k = 0; k < repeats + 1; ++k) {
            VectorXd guess = VectorXd::Zero(6);
            if (warm) {
                // Warm: start from the solution at 0.99 times the tension (untimed), as
                // `tdcr bench` does.
                tension = 0.99 * tension_full;
                guess = solve<N>(guess, settings);
            }
            tension = tension_full;
            evaluations = 0;
            double t0 = thread_cpu_ms();
            solution = solve<N>(guess, settings);
            double t1 = thread_cpu_ms();
            evals = evaluations;
            if (k > 0) times.push_back(t1 - t0);  // the first solve warms the caches
        }
        std::sort(times.begin(), times.end());
        shooting<N>(solution);
        Vector3d tip = Y.block<3, 1>(0, N - 1);
        std::printf("%s %s %d %.6f %ld %.3e\n", name, warm ? "warm" : "cold", steps,
                    times[times.size() / 2], evals, (tip - reference).norm());
    }
}

template <int N>
static void run_both(char which, int repeats, const Settings& settings) {
    if (which == 'S' || which == 'A') {
        helical = false;
        tip_force.setZero();
        run_case<N>("S", Vector3d(0.151823122, 0.0, -0.159529649), 2.94, repeats, settings);
    }
    if (which == 'H' || which == 'A') {
        helical = true;
        tip_force = Vector3d(0, 0, -0.196);
        run_case<N>("H", Vector3d(0.155616146, 0.0596521926, -0.158035195), 4.91, repeats, settings);
    }
}

// Usage: till_driver CASE STEPS STOP REPEATS, CASE one of S, H, A (both); STEPS one of the
// instantiated RK4 step counts below.
int main(int argc, char** argv) {
    if (argc != 5) {
        std::fprintf(stderr, "usage: %s S|H|A STEPS STOP REPEATS\n", argv[0]);
        return 2;
    }
    R0 << 0, 0, 1, 0, 1, 0, -1, 0, 0;
    char which = argv[1][0];
    int steps = std::atoi(argv[2]);
    Settings settings{std::atof(argv[3])};
    int repeats = std::atoi(argv[4]);
    switch (steps) {
        case 16: run_both<17>(which, repeats, settings); break;
        case 24: run_both<25>(which, repeats, settings); break;
        case 32: run_both<33>(which, repeats, settings); break;
        case 48: run_both<49>(which, repeats, settings); break;
        case 64: run_both<65>(which, repeats, settings); break;
        case 99: run_both<100>(which, repeats, settings); break;
        case 108: run_both<109>(which, repeats, settings); break;
        case 128: run_both<129>(which, repeats, settings); break;
        case 256: run_both<257>(which, repeats, settings); break;
        default:
            std::fprintf(stderr, "steps must be one of 16 24 32 48 64 99 108 128 256 (got %d)\n", steps);
            return 2;
    }
    return 0;
}
