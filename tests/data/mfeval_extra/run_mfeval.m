function run_mfeval(tir, infile, outfile)
% Evaluate MFeval 4.3.1 (mfeval.Solver().fullSteadyState) row by row: each row of infile
% [Fz kappa alpha gamma phit Vx P omega useMode ncols] is one call with ncols input columns.
% outfile gets the 30 outputs plus the residual of MFeval's own MF 6.2 vertical-force equation at
% the Rl it returned (0 for other FITTYPs). Called by make_tables.py; needs the +mfeval package
% and the compatibility shims on the Octave path.
  warning('off', 'all');
  params = mfeval.readTIR(tir);
  solver = mfeval.Solver();
  rows = dlmread(infile, ',');
  out = zeros(size(rows, 1), 31);
  for i = 1:size(rows, 1)
    ncols = rows(i, 10);
    r = solver.fullSteadyState(params, rows(i, 1:ncols), rows(i, 9));
    residual = 0;
    if params.FITTYP == 62
      gamma = r(9);
      if rows(i, 9) < 200
        gamma = min(max(gamma, params.CAMMIN), params.CAMMAX);
      end
      omega = r(19);
      R0 = params.UNLOADED_RADIUS;
      Romega = R0 * (params.Q_RE0 + params.Q_V1 * ((omega * R0) / params.LONGVL)^2);
      dpi = (r(12) - params.NOMPRES) / params.NOMPRES;
      fz = solver.calculateFz62(params, gamma, omega, Romega, dpi, r(20), r(1), r(2));
      residual = fz - r(3);
    end
    out(i, :) = [r, residual];
  end
  fid = fopen(outfile, 'w');
  fprintf(fid, [repmat('%.17g,', 1, 30), '%.17g\n'], out.');
  fclose(fid);
end
