#!/usr/bin/env python3
"""Tests of the fallback preprocessor funitproc.py (standard library unittest; run by ctest).

Each bad input must be rejected with its file:line, and the transformation must keep the
line numbers of the .pf file.
"""
import glob
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import funitproc  # noqa: E402


class PreprocessorTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def write(self, name, text):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(textwrap.dedent(text).lstrip("\n"))
        return path

    def run_tool(self, *args):
        return subprocess.run([sys.executable, os.path.join(HERE, "funitproc.py"), *args],
                              capture_output=True, text=True, check=False)

    def assert_rejected(self, name, text, line, fragment):
        path = self.write(name, text)
        out = os.path.join(self.tmp.name, "out.F90")
        proc = self.run_tool("preprocess", path, out)
        self.assertNotEqual(proc.returncode, 0, proc.stderr)
        self.assertIn(f"{name}:{line}:", proc.stderr)
        self.assertIn(fragment, proc.stderr)
        self.assertFalse(os.path.exists(out))

    def assert_accepted(self, name, text):
        path = self.write(name, text)
        proc = self.run_tool("preprocess", path, os.path.join(self.tmp.name, "out.F90"))
        self.assertEqual(proc.returncode, 0, proc.stderr)

    def test_assert_keeps_line_numbers(self):
        path = self.write("test_a.pf", """
            module test_a
              use funit
              implicit none
            contains
              @test
              subroutine test_x()
                ! a comment line
                @assertEqual(1, 1, message='it''s fine!')
                @assertTrue(.true.)
              end subroutine test_x
            end module test_a
            """)
        out = os.path.join(self.tmp.name, "test_a.F90")
        proc = self.run_tool("preprocess", path, out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(out, encoding="utf-8") as handle:
            lines = handle.read().split("\n")
        self.assertTrue(lines[0].startswith('# 1 "'))
        body = lines[1:]                           # body[k] is line k+1 of the .pf
        self.assertEqual(body[4].strip(), "!@test")
        self.assertEqual(
            body[7].strip(),
            "call assertEqual(1, 1, message='it''s fine!', location=SourceLocation('test_a.pf', 8));"
            " if (anyExceptions()) return")
        self.assertEqual(body[8].strip(),
                         "call assertTrue(.true., location=SourceLocation('test_a.pf', 9));"
                         " if (anyExceptions()) return")
        self.assertEqual(body[9].strip(), "end subroutine test_x")

    # What real pFUnit 4.12 does not compile (tests/README.md, PFUNIT.md).

    def test_multi_line_assert(self):
        self.assert_rejected("test_m.pf", """
            module test_m
              use funit
            contains
              @test
              subroutine test_x()
                @assertEqual(1, &
                     1)
              end subroutine test_x
            end module test_m
            """, 6, "must be on one line")

    def test_comment_after_assert(self):
        self.assert_rejected("test_n.pf", """
            module test_n
              use funit
            contains
              @test
              subroutine test_x()
                @assertEqual(1, 1, message='a ! in a string is fine') ! but not this
              end subroutine test_x
            end module test_n
            """, 6, "no comment after an @assert")

    def scalar_module(self, name, assertion):
        return f"""
            module {name}
              use funit
              use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
              implicit none
              real :: table(3, 3)
            contains
              @test
              subroutine test_x()
                real :: x(3), y, m(2, 2)
                character(len=8) :: s
                x = 1.0
                y = 1.0
                m = 1.0
                s = 'abc'
                table = 1.0
                {assertion}
              end subroutine test_x
            end module {name}
            """

    def test_array_where_a_scalar_is_taken(self):
        bad = {
            "@assertIsFinite(x)": "the array 'x'",
            "@assertIsNaN(x(2:3))": "array section 'x(2:3)'",
            "@assertIsFinite([y, y])": "array constructor",
            "@assertIsFinite(2*x + y)": "the array 'x'",
            "@assertTrue(m > 0)": "the array 'm' (rank 2)",
            "@assertFalse(table(:, :) < 0, message='no')": "array section 'table(:, :)'",
            "@assertTrue(ieee_is_finite(y) .and. (m(1:2, :) > 0))": "array section",
        }
        for k, (assertion, fragment) in enumerate(bad.items()):
            with self.subTest(assertion=assertion):
                self.assert_rejected(f"test_s{k}.pf", self.scalar_module(f"test_s{k}", assertion),
                                     16, fragment)

    def test_scalars_and_what_pfunit_accepts(self):
        good = ["@assertIsFinite(x(2))", "@assertIsNaN(sum(x))", "@assertIsFinite(y)",
                "@assertTrue(all(ieee_is_finite(x)))", "@assertTrue(all(m(:, 1) > 0))",
                "@assertTrue(x > 0)", "@assertTrue([.true., .true.])", "@assertFalse(x(1:2) < 0)",
                "@assertTrue(s(1:2) == 'ab')", "@assertTrue(size(table, 1) == 3)",
                "@assertEqual(x, x)", "@assertTrue(table(1, 1) == 1.0, message='x(:)')"]
        for k, assertion in enumerate(good):
            with self.subTest(assertion=assertion):
                self.assert_accepted(f"test_g{k}.pf", self.scalar_module(f"test_g{k}", assertion))

    def mpi_module(self, name, lines="", npes="1"):
        return f"""
            module {name}
              use funit
              use pfunit
              {lines}
              implicit none
            contains
              @mpitest(npes=[{npes}])
              subroutine test_x(this)
                class(MpiTestMethod), intent(inout) :: this
              end subroutine test_x
            end module {name}
            """

    def test_names_that_clash_with_pfunit(self):
        self.assert_rejected("test_p1.pf", self.mpi_module("test_p1", "use mpi_f08"), 4,
                             "without 'only:'")
        self.assert_rejected("test_p2.pf", self.mpi_module(
            "test_p2", "use mpi_f08, only: f08_comm => MPI_Comm, MPI_SUM"), 4, "'MPI_SUM'")
        self.assert_rejected("test_p3.pf", self.mpi_module(
            "test_p3", "integer :: nprocs, mpi_comm_world"), 4, "'mpi_comm_world'")
        self.assert_accepted("test_p4.pf", self.mpi_module(
            "test_p4", "use mpi_f08, only: f08_comm => MPI_Comm, f08_sum => MPI_SUM"))
        # without pfunit, mpi_f08 names are the module's own business
        self.assert_accepted("test_p5.pf", """
            module test_p5
              use funit
              use mpi_f08, only: MPI_Comm
            contains
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_p5
            """)

    def test_procedure_named_like_mpi(self):
        self.assert_rejected("test_p6.pf", """
            module test_p6
              use funit
              use pfunit
            contains
              subroutine MPI_helper()
              end subroutine MPI_helper
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_p6
            """, 5, "'MPI_helper'")

    def test_procedure_named_like_funit_export(self):
        """funit exports `run`: a module procedure `run` beside `use funit` (no only:) does not
        compile under real pFUnit 4.12 (tests/unit/test_shared_pairs.pf had one)."""
        self.assert_rejected("test_f1.pf", """
            module test_f1
              use funit
            contains
              subroutine run(x)
                real, intent(out) :: x
                x = 1
              end subroutine run
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_f1
            """, 4, "'run' is a name module funit exports")
        self.assert_rejected("test_f2.pf", """
            module test_f2
              use funit
              implicit none
              integer :: finalize = 0
            contains
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_f2
            """, 4, "'finalize'")
        # with only:, or as a local variable of a procedure, the name is the module's own
        self.assert_accepted("test_f3.pf", """
            module test_f3
              use funit, only: assertTrue, anyExceptions, SourceLocation
            contains
              subroutine run()
              end subroutine run
              @test
              subroutine test_x()
                integer :: run_count
                run_count = 1
                @assertTrue(run_count == 1)
              end subroutine test_x
            end module test_f3
            """)
        self.assert_accepted("test_f4.pf", """
            module test_f4
              use funit
            contains
              @test
              subroutine test_x()
                integer :: run
                run = 1
              end subroutine test_x
            end module test_f4
            """)

    def test_project_pf_files_pass(self):
        """Every .pf file of the project passes the rules (real pFUnit compiles them)."""
        root = os.path.dirname(os.path.dirname(HERE))
        files = sorted(glob.glob(os.path.join(root, "tests", "**", "*.pf"), recursive=True))
        self.assertGreater(len(files), 30)
        for path in files:
            with self.subTest(pf=os.path.relpath(path, root)):
                proc = self.run_tool("preprocess", path, os.path.join(self.tmp.name, "out.F90"))
                self.assertEqual(proc.returncode, 0, proc.stderr)

    def test_module_name_must_match_file(self):
        self.assert_rejected("test_b.pf", """
            module test_other
              use funit
            contains
              @test
              subroutine test_x()
              end subroutine test_x
            end module test_other
            """, 1, "must be named like the file")

    def test_unknown_directive(self):
        self.assert_rejected("test_c.pf", """
            module test_c
              use funit
            contains
              @testcase
              subroutine test_x()
              end subroutine test_x
            end module test_c
            """, 4, "unsupported directive")

    def test_test_with_arguments(self):
        self.assert_rejected("test_d.pf", """
            module test_d
              use funit
            contains
              @test
              subroutine test_x(n)
                integer, intent(in) :: n
              end subroutine test_x
            end module test_d
            """, 5, "must take no arguments")

    def test_directive_without_subroutine(self):
        self.assert_rejected("test_e.pf", """
            module test_e
              use funit
            contains
              @test
              function test_x() result(r)
                integer :: r
                r = 1
              end function test_x
            end module test_e
            """, 5, "must be followed by a subroutine")

    def test_reserved_name(self):
        self.assert_rejected("test_f.pf", """
            module test_f
              use funit
            contains
              @test
              subroutine suite()
              end subroutine suite
            end module test_f
            """, 5, "reserved")

    def test_mpitest_needs_npes(self):
        self.assert_rejected("test_g.pf", """
            module test_g
              use funit
              use pfunit
            contains
              @mpitest
              subroutine test_x(this)
                class(MpiTestMethod), intent(inout) :: this
              end subroutine test_x
            end module test_g
            """, 5, "npes")

    def test_unterminated_assert(self):
        self.assert_rejected("test_h.pf", """
            module test_h
              use funit
            contains
              @test
              subroutine test_x()
                @assertTrue(.true.
              end subroutine test_x
            end module test_h
            """, 6, "must end with ')'")

    def test_no_tests(self):
        self.assert_rejected("test_i.pf", """
            module test_i
              use funit
            end module test_i
            """, 1, "no @test")

    def test_mpitest_in_serial_driver(self):
        path = self.write("test_j.pf", self.mpi_module("test_j", npes="1, 2"))
        out = os.path.join(self.tmp.name, "drv.F90")
        proc = self.run_tool("driver", "--name", "t", "-o", out, path)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("MPI_PES", proc.stderr)
        proc = self.run_tool("driver", "--mpi", "--name", "t", "-o", out, path)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(out, encoding="utf-8") as handle:
            self.assertIn("call pfunit_run_mpi_test('test_j', 'test_x', pf1_t1, [1, 2])",
                          handle.read())

    def test_npes_larger_than_mpi_pes(self):
        path = self.write("test_k.pf", self.mpi_module("test_k", npes="4"))
        out = os.path.join(self.tmp.name, "drv.F90")
        proc = self.run_tool("driver", "--mpi", "--np", "2", "--name", "t", "-o", out, path)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("test_k.pf:8:", proc.stderr)
        self.assertIn("raise MPI_PES", proc.stderr)

    def test_options(self):
        self.assertEqual(funitproc.parse_options("npes=[1, 3], ifdef=FOO"),
                         {"npes": [1, 3], "ifdef": "FOO"})
        self.assertEqual(funitproc.split_comment("a = '!' ! c"), ("a = '!' ", "! c"))


if __name__ == "__main__":
    unittest.main()
