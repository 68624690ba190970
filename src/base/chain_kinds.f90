!> Numeric kinds used throughout impactchain (double precision reals, 64-bit counters) and pi.
!> Infrastructure, no model section.
module chain_kinds
    use, intrinsic :: iso_fortran_env, only: wp => real64, i8 => int64
    implicit none
    private
    public :: wp, i8, pi, two_pi

    real(wp), parameter :: pi = 3.14159265358979323846264338327950288_wp
    real(wp), parameter :: two_pi = 2*pi

end module chain_kinds
